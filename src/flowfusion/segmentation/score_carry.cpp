#include "flowfusion/segmentation/score_carry.h"

#include <limits>
#include <vector>

namespace ff {

namespace {

// The nearest surface's score at the 2x2 pixels from (u0, v0): the splat of one carried pixel.
// Raw pointers and a branch-free path inside the image: with cv::Mat::at and four bounds checks
// per neighbour the compiler reloaded each Mat's data and step after every float store.
struct Splat {
  float* out;
  float* zbuf;
  int cols, rows;

  void add(int u0, int v0, double qz, float b) const {
    if (u0 >= 0 && v0 >= 0 && u0 < cols - 1 && v0 < rows - 1) {
      const size_t i = static_cast<size_t>(v0) * cols + u0;
      keep(i, qz, b);
      keep(i + 1, qz, b);
      keep(i + cols, qz, b);
      keep(i + cols + 1, qz, b);
      return;
    }
    // At the border: the pixels in the image.
    if (u0 < -1 || v0 < -1 || u0 >= cols || v0 >= rows) return;
    for (int v = v0; v <= v0 + 1; ++v)
      for (int u = u0; u <= u0 + 1; ++u)
        if (u >= 0 && v >= 0 && u < cols && v < rows) keep(static_cast<size_t>(v) * cols + u, qz, b);
  }
  // The nearer surface wins pixel i.
  void keep(size_t i, double qz, float b) const {
    if (qz < zbuf[i]) {
      zbuf[i] = static_cast<float>(qz);
      out[i] = b;
    }
  }
};

}  // namespace

cv::Mat carryScores(const cv::Mat& prev_scores, const cv::Mat& prev_depth, const CameraIntrinsics& cam,
                    const SE3& T_cur_prev, float fill) {
  cv::Mat out(prev_scores.size(), CV_32F, cv::Scalar(fill));
  cv::Mat zbuf(prev_scores.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  const Splat splat{out.ptr<float>(), zbuf.ptr<float>(), out.cols, out.rows};
  const int cols = prev_depth.cols;
  std::vector<double> qzs(cols), us(cols), vs(cols);
  const Eigen::Matrix3d R = T_cur_prev.linear();
  const Eigen::Vector3d t = T_cur_prev.translation();
  const double r00 = R(0, 0), r01 = R(0, 1), r02 = R(0, 2), r10 = R(1, 0), r11 = R(1, 1), r12 = R(1, 2);
  const double r20 = R(2, 0), r21 = R(2, 1), r22 = R(2, 2), t0 = t.x(), t1 = t.y(), t2 = t.z();
  const double fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy;
  for (int y = 0; y < prev_depth.rows; ++y) {
    const float* b_row = prev_scores.ptr<float>(y);
    const float* z_row = prev_depth.ptr<float>(y);
    // The row's points and pixels in a loop the compiler vectorises: the same double operations,
    // in the same order, as T_cur_prev * cam.backproject(x, y, z) and cam.project(q).
    double *qz_out = qzs.data(), *u_out = us.data(), *v_out = vs.data();
    for (int x = 0; x < cols; ++x) {
      const double z = z_row[x];
      const double px = (x - cx) * z / fx, py = (y - cy) * z / fy;
      const double qx = r00 * px + r01 * py + r02 * z + t0;
      const double qy = r10 * px + r11 * py + r12 * z + t1;
      const double qz = r20 * px + r21 * py + r22 * z + t2;
      qz_out[x] = qz;
      u_out[x] = fx * qx / qz + cx;
      v_out[x] = fy * qy / qz + cy;
    }
    for (int x = 0; x < cols; ++x) {
      if (z_row[x] <= 0 || qzs[x] <= 0) continue;
      // Splat to the 2x2 neighbourhood so that no holes open up.
      // Cast only here: a pixel without depth or behind the camera may project beyond int's range.
      splat.add(static_cast<int>(us[x]), static_cast<int>(vs[x]), qzs[x], b_row[x]);
    }
  }
  return out;
}

cv::Mat staticWeights(const cv::Mat& scores) {
  if (scores.empty()) return {};
  cv::Mat w;
  cv::subtract(cv::Scalar(1.0), scores, w);
  return w;
}

}  // namespace ff

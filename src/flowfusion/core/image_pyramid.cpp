#include "flowfusion/core/image_pyramid.h"

#include <opencv2/core/utility.hpp>

namespace ff {

cv::Mat downsampleIntensity(const cv::Mat& img) {
  CV_Assert(img.type() == CV_32FC1);
  cv::Mat out(img.rows / 2, img.cols / 2, CV_32FC1);
  cv::parallel_for_(cv::Range(0, out.rows), [&](const cv::Range& r) {
    for (int y = r.start; y < r.end; ++y) {
      const float* a = img.ptr<float>(2 * y);
      const float* b = img.ptr<float>(2 * y + 1);
      float* o = out.ptr<float>(y);
      for (int x = 0; x < out.cols; ++x)
        o[x] = 0.25f * (a[2 * x] + a[2 * x + 1] + b[2 * x] + b[2 * x + 1]);
    }
  });
  return out;
}

cv::Mat downsampleDepth(const cv::Mat& depth, float max_rel_spread) {
  CV_Assert(depth.type() == CV_32FC1);
  cv::Mat out(depth.rows / 2, depth.cols / 2, CV_32FC1);
  cv::parallel_for_(cv::Range(0, out.rows), [&](const cv::Range& r) {
    for (int y = r.start; y < r.end; ++y) {
      const float* a = depth.ptr<float>(2 * y);
      const float* b = depth.ptr<float>(2 * y + 1);
      float* o = out.ptr<float>(y);
      for (int x = 0; x < out.cols; ++x) {
        const float d[4] = {a[2 * x], a[2 * x + 1], b[2 * x], b[2 * x + 1]};
        float dmin = 1e30f;
        for (float v : d)
          if (v > 0 && v < dmin) dmin = v;
        float sum = 0;
        int n = 0;
        for (float v : d)
          if (v > 0 && v <= dmin * (1.0f + max_rel_spread)) {
            sum += v;
            ++n;
          }
        o[x] = n ? sum / n : 0.0f;
      }
    }
  });
  return out;
}

namespace {

void gradients(const cv::Mat& img, cv::Mat& gx, cv::Mat& gy, bool depth) {
  gx = cv::Mat::zeros(img.size(), CV_32FC1);
  gy = cv::Mat::zeros(img.size(), CV_32FC1);
  const int W = img.cols, H = img.rows;
  cv::parallel_for_(cv::Range(1, H - 1), [&](const cv::Range& r) {
    for (int y = r.start; y < r.end; ++y) {
      const float* m = img.ptr<float>(y);
      const float* u = img.ptr<float>(y - 1);
      const float* d = img.ptr<float>(y + 1);
      float* ox = gx.ptr<float>(y);
      float* oy = gy.ptr<float>(y);
      for (int x = 1; x < W - 1; ++x) {
        if (depth && (m[x - 1] <= 0 || m[x + 1] <= 0 || u[x] <= 0 || d[x] <= 0)) continue;
        ox[x] = 0.5f * (m[x + 1] - m[x - 1]);
        oy[x] = 0.5f * (d[x] - u[x]);
      }
    }
  });
}

}  // namespace

std::vector<PyramidLevel> buildPyramid(const cv::Mat& intensity, const cv::Mat& depth,
                                       const CameraIntrinsics& camera, int levels, int first_gradient_level) {
  std::vector<PyramidLevel> pyr(levels);
  pyr[0].intensity = intensity;
  pyr[0].depth = depth;
  pyr[0].camera = camera;
  for (int l = 1; l < levels; ++l) {
    pyr[l].intensity = downsampleIntensity(pyr[l - 1].intensity);
    pyr[l].depth = downsampleDepth(pyr[l - 1].depth);
    pyr[l].camera = camera.atLevel(l);
  }
  for (int l = first_gradient_level; l < levels; ++l) {
    gradients(pyr[l].intensity, pyr[l].grad_x, pyr[l].grad_y, false);
    gradients(pyr[l].depth, pyr[l].dgrad_x, pyr[l].dgrad_y, true);
  }
  return pyr;
}

}  // namespace ff

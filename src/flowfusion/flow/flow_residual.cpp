#include "flowfusion/flow/flow_residual.h"

#include <algorithm>
#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/core/rgbd_frame.h"

namespace ff {

cv::Mat egoFlow(const cv::Mat& depth_a, const CameraIntrinsics& camera, const SE3& T_cam_b_cam_a) {
  if (depth_a.empty() || depth_a.type() != CV_32FC1) throw InputError("egoFlow: expected a CV_32FC1 depth image");
  if (camera.width != depth_a.cols || camera.height != depth_a.rows)
    throw InputError("egoFlow: camera size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                     " does not match the depth image " + std::to_string(depth_a.cols) + "x" +
                     std::to_string(depth_a.rows));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const Eigen::Matrix3f R = T_cam_b_cam_a.rotation().cast<float>();
  const Eigen::Vector3f t = T_cam_b_cam_a.translation().cast<float>();
  const float fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  cv::Mat flow(depth_a.size(), CV_32FC2);
  cv::parallel_for_(cv::Range(0, depth_a.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* d = depth_a.ptr<float>(v);
      auto* out = flow.ptr<cv::Vec2f>(v);
      // R * (ray * z) + t, with the ray's rotated part linear in u along the row.
      const Eigen::Vector3f row_base = R * Eigen::Vector3f(-cx / fx, (v - cy) / fy, 1.f);
      const Eigen::Vector3f du = R.col(0) / fx;
      for (int u = 0; u < depth_a.cols; ++u) {
        const float z = d[u];
        if (!(z > 0.f) || !std::isfinite(z)) {
          out[u] = {nan, nan};
          continue;
        }
        const Eigen::Vector3f p = (row_base + du * static_cast<float>(u)) * z + t;
        if (p.z() <= 1e-6f) {
          out[u] = {nan, nan};
          continue;
        }
        out[u] = {fx * p.x() / p.z() + cx - u, fy * p.y() / p.z() + cy - v};
      }
    }
  });
  return flow;
}

namespace {

// Optical flow - ego flow per pixel (CV_32FC2), NaN where either is invalid or the ego flow leaves
// the image.
cv::Mat residualVectors(const FlowField& flow, const cv::Mat& ego_flow, const char* who) {
  if (flow.uv.empty() || flow.uv.type() != CV_32FC2) throw InputError(std::string(who) + ": optical flow is not CV_32FC2");
  if (ego_flow.empty() || ego_flow.type() != CV_32FC2) throw InputError(std::string(who) + ": ego flow is not CV_32FC2");
  const FlowField of = resizeFlow(flow, ego_flow.size());
  cv::Mat d(ego_flow.size(), CV_32FC2);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float max_u = static_cast<float>(d.cols - 1), max_v = static_cast<float>(d.rows - 1);
  for (int v = 0; v < d.rows; ++v) {
    const auto* a = of.uv.ptr<cv::Vec2f>(v);
    const auto* e = ego_flow.ptr<cv::Vec2f>(v);
    auto* o = d.ptr<cv::Vec2f>(v);
    // NaN propagates through the arithmetic, which is what marks invalid pixels. A pixel the ego
    // flow takes outside the image was not in view in the other frame: its optical flow matched
    // something else (content entering at the border), so it has no residual.
    for (int u = 0; u < d.cols; ++u) {
      const float tu = static_cast<float>(u) + e[u][0], tv = static_cast<float>(v) + e[u][1];
      const bool in_view = tu >= 0.f && tu <= max_u && tv >= 0.f && tv <= max_v;
      o[u] = in_view ? cv::Vec2f(a[u][0] - e[u][0], a[u][1] - e[u][1]) : cv::Vec2f(nan, nan);
    }
  }
  return d;
}

// Where each pixel x of a flow's first image lands, x + uv(x), as a remap map (CV_32FC2); a NaN
// flow lands at (-2, -2), outside the image.
cv::Mat landingPositions(const cv::Mat& uv) {
  cv::Mat out(uv.size(), CV_32FC2);
  for (int v = 0; v < out.rows; ++v) {
    const auto* f = uv.ptr<cv::Vec2f>(v);
    auto* o = out.ptr<cv::Vec2f>(v);
    for (int u = 0; u < out.cols; ++u)
      o[u] = std::isnan(f[u][0]) || std::isnan(f[u][1]) ? cv::Vec2f(-2.f, -2.f) : cv::Vec2f(u + f[u][0], v + f[u][1]);
  }
  return out;
}

// The affine field c + A x (x normalised to [-0.5, 0.5) over the image) and, with the parallax,
// the flow a small translation error t of the camera adds at inverse depth iz:
// iz (fx t_x - (u - c_x) t_z, fy t_y - (v - c_y) t_z). Each row of the field is q . p with
// q = (1, x, y, iz, -(u - c_x) iz) for du and (1, x, y, iz, -(v - c_y) iz) for dv: pu = (du's c, A
// row, fx t_x, t_z), pv = (dv's c, A row, fy t_y, t_z), t_z shared.
using Vector5d = Eigen::Matrix<double, 5, 1>;
struct ErrorField {
  Vector5d pu = Vector5d::Zero(), pv = Vector5d::Zero();
};

// A sample of the residual field: the residual vector and its two rows' q (iz 0 without a depth).
struct FieldSample {
  double du, dv;
  Vector5d qu, qv;
};

FieldSample fieldSample(double x, double y, double du, double dv, double u_c_px, double v_c_px, double iz) {
  FieldSample s{du, dv, Vector5d(), Vector5d()};
  s.qu << 1.0, x, y, iz, -u_c_px * iz;
  s.qv << 1.0, x, y, iz, -v_c_px * iz;
  return s;
}

// The samples on a 4-pixel grid where d is finite (and, with a depth, the depth is valid) and
// left_out (CV_8U, if given) is 0.
std::vector<FieldSample> fieldSamples(const cv::Mat& d, const cv::Mat& depth, const CameraIntrinsics* camera,
                                      const cv::Mat& left_out = {}) {
  std::vector<FieldSample> samples;
  constexpr int kGridPx = 4;
  for (int v = 0; v < d.rows; v += kGridPx) {
    const auto* row = d.ptr<cv::Vec2f>(v);
    for (int u = 0; u < d.cols; u += kGridPx) {
      if (!std::isfinite(row[u][0]) || !std::isfinite(row[u][1])) continue;
      if (!left_out.empty() && left_out.at<uint8_t>(v, u)) continue;
      double iz = 0, u_c = 0, v_c = 0;
      if (camera) {
        const float z = depth.at<float>(v, u);
        if (!(z > 0) || !std::isfinite(z)) continue;
        iz = 1.0 / z;
        u_c = u - camera->cx;
        v_c = v - camera->cy;
      }
      samples.push_back(fieldSample(static_cast<double>(u) / d.cols - 0.5, static_cast<double>(v) / d.rows - 0.5,
                                    row[u][0], row[u][1], u_c, v_c, iz));
    }
  }
  return samples;
}

// The field's unknowns from the two rows' weighted normal equations (q q^T and q d sums): the
// affine part's two 3x3 systems, or with the parallax one system of the nine unknowns (pu's five,
// pv's first four, t_z shared) with a small relative ridge: where the depths barely vary the
// parallax and the affine part are interchangeable (the field, not its parameters, is the answer).
void solveField(const Eigen::Matrix<double, 5, 5>& Nu, const Vector5d& ru, const Eigen::Matrix<double, 5, 5>& Nv,
                const Vector5d& rv, bool parallax, ErrorField& field) {
  if (!parallax) {
    field.pu.head<3>() = Eigen::LDLT<Eigen::Matrix3d>(Nu.topLeftCorner<3, 3>()).solve(ru.head<3>());
    field.pv.head<3>() = Eigen::LDLT<Eigen::Matrix3d>(Nv.topLeftCorner<3, 3>()).solve(rv.head<3>());
    return;
  }
  constexpr int kU[5] = {0, 1, 2, 3, 8}, kV[5] = {4, 5, 6, 7, 8};
  Eigen::Matrix<double, 9, 9> N = Eigen::Matrix<double, 9, 9>::Zero();
  Eigen::Matrix<double, 9, 1> r = Eigen::Matrix<double, 9, 1>::Zero();
  for (int a = 0; a < 5; ++a) {
    r[kU[a]] += ru[a];
    r[kV[a]] += rv[a];
    for (int b = 0; b < 5; ++b) {
      N(kU[a], kU[b]) += Nu(a, b);
      N(kV[a], kV[b]) += Nv(a, b);
    }
  }
  constexpr double kRidge = 1e-6;
  N.diagonal() *= 1.0 + kRidge;
  const Eigen::Matrix<double, 9, 1> p = Eigen::LDLT<Eigen::Matrix<double, 9, 9>>(N).solve(r);
  for (int a = 0; a < 5; ++a) {
    field.pu[a] = p[kU[a]];
    field.pv[a] = p[kV[a]];
  }
}

// Cauchy IRLS of scale scale_px from the zero field (6 iterations); without the parallax its
// unknowns stay 0.
ErrorField fitErrorField(const std::vector<FieldSample>& samples, double scale_px, bool parallax) {
  ErrorField field;
  constexpr size_t kMinSamples = 50;  // fewer: no field (a frame almost without depth)
  constexpr int kIterations = 6;
  if (samples.size() < kMinSamples) return field;
  const double inv_scale2 = 1.0 / (scale_px * scale_px);
  for (int it = 0; it < kIterations; ++it) {
    Eigen::Matrix<double, 5, 5> Nu = Eigen::Matrix<double, 5, 5>::Zero(), Nv = Nu;
    Vector5d ru = Vector5d::Zero(), rv = Vector5d::Zero();
    for (const FieldSample& s : samples) {
      const double eu = s.du - s.qu.dot(field.pu), ev = s.dv - s.qv.dot(field.pv);
      const double w = 1.0 / (1.0 + (eu * eu + ev * ev) * inv_scale2);  // Cauchy
      Nu.noalias() += w * s.qu * s.qu.transpose();
      Nv.noalias() += w * s.qv * s.qv.transpose();
      ru.noalias() += w * s.du * s.qu;
      rv.noalias() += w * s.dv * s.qv;
    }
    solveField(Nu, ru, Nv, rv, parallax, field);
  }
  return field;
}

// d(x) -= field(x) over the image, in place (at the samples' grid and between them alike).
void subtractField(cv::Mat& d, const ErrorField& field, const cv::Mat& depth, const CameraIntrinsics* camera) {
  for (int v = 0; v < d.rows; ++v) {
    auto* row = d.ptr<cv::Vec2f>(v);
    const double y = static_cast<double>(v) / d.rows - 0.5;
    for (int u = 0; u < d.cols; ++u) {
      const float z = camera ? depth.at<float>(v, u) : 0.f;
      const double iz = z > 0 && std::isfinite(z) ? 1.0 / z : 0.0;
      const FieldSample s = fieldSample(static_cast<double>(u) / d.cols - 0.5, y, 0, 0,
                                        camera ? u - camera->cx : 0.0, camera ? v - camera->cy : 0.0, iz);
      row[u] -= cv::Vec2f(static_cast<float>(s.qu.dot(field.pu)), static_cast<float>(s.qv.dot(field.pv)));
    }
  }
}

// |d(x)| per pixel (CV_32FC1), NaN where d is.
cv::Mat lengths(const cv::Mat& d) {
  cv::Mat r(d.size(), CV_32FC1);
  for (int v = 0; v < d.rows; ++v) {
    const auto* row = d.ptr<cv::Vec2f>(v);
    float* o = r.ptr<float>(v);
    for (int u = 0; u < d.cols; ++u) o[u] = std::hypot(row[u][0], row[u][1]);
  }
  return r;
}

}  // namespace

cv::Mat flowResidual(const FlowField& flow, const cv::Mat& ego_flow) {
  return lengths(residualVectors(flow, ego_flow, "flowResidual"));
}

cv::Mat smallestFlowResidual(const FlowField& flow, const std::vector<cv::Mat>& depths,
                             const CameraIntrinsics& camera, const SE3& T_cam_b_cam_a) {
  if (depths.empty()) throw InputError("smallestFlowResidual: no depth to try");
  cv::Mat smallest(camera.height, camera.width, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (const cv::Mat& depth : depths) {
    if (depth.type() != CV_32FC1 || depth.cols != camera.width || depth.rows != camera.height)
      throw InputError("smallestFlowResidual: every depth must be CV_32FC1 of the camera's size");
    const cv::Mat r = flowResidual(flow, egoFlow(depth, camera, T_cam_b_cam_a));
    // NaN compares false: a pixel takes r where r is finite and it has none yet or a larger one.
    r.copyTo(smallest, (r == r) & ~(smallest <= r));
  }
  return smallest;
}

cv::Mat flowResidualWithoutAffine(const FlowField& flow, const cv::Mat& ego_flow, double scale_px) {
  if (!(scale_px > 0) || !std::isfinite(scale_px))
    throw InputError("flowResidualWithoutAffine: the fit's scale must be a finite number of pixels > 0");
  cv::Mat d = residualVectors(flow, ego_flow, "flowResidualWithoutAffine");
  subtractField(d, fitErrorField(fieldSamples(d, {}, nullptr), scale_px, false), {}, nullptr);
  return lengths(d);
}

cv::Mat flowResidualWithoutPoseError(const FlowField& flow, const cv::Mat& ego_flow, const cv::Mat& depth,
                                     const CameraIntrinsics& camera, double scale_px, const cv::Mat& movers) {
  if (!(scale_px > 0) || !std::isfinite(scale_px))
    throw InputError("flowResidualWithoutPoseError: the fit's scale must be a finite number of pixels > 0");
  cv::Mat d = residualVectors(flow, ego_flow, "flowResidualWithoutPoseError");
  if (depth.type() != CV_32FC1 || depth.size() != d.size() || camera.width != d.cols || camera.height != d.rows)
    throw InputError("flowResidualWithoutPoseError: the depth and camera must be CV_32FC1 of the ego flow's size");
  if (!movers.empty() && (movers.type() != CV_8UC1 || movers.size() != d.size()))
    throw InputError("flowResidualWithoutPoseError: the movers must be CV_8UC1 of the ego flow's size");
  subtractField(d, fitErrorField(fieldSamples(d, depth, &camera, movers), scale_px, true), depth, &camera);
  return lengths(d);
}

cv::Mat inconsistentFlow(const FlowField& forward, const FlowField& backward, double tolerance_px) {
  if (forward.uv.type() != CV_32FC2 || backward.uv.type() != CV_32FC2 || forward.uv.size() != backward.uv.size() ||
      forward.uv.empty())
    throw InputError("inconsistentFlow: both flows must be CV_32FC2 of one size");
  if (!(tolerance_px >= 0) || !std::isfinite(tolerance_px))
    throw InputError("inconsistentFlow: the tolerance must be a finite number of pixels >= 0");
  cv::Mat back;
  cv::remap(backward.uv, back, landingPositions(forward.uv), cv::noArray(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  constexpr double kShareOfFlow = 0.05;
  cv::Mat out(forward.uv.size(), CV_8U, cv::Scalar(0));
  for (int v = 0; v < out.rows; ++v) {
    const auto* f = forward.uv.ptr<cv::Vec2f>(v);
    const auto* b = back.ptr<cv::Vec2f>(v);
    auto* o = out.ptr<uint8_t>(v);
    for (int u = 0; u < out.cols; ++u) {
      const double gap = std::hypot(f[u][0] + b[u][0], f[u][1] + b[u][1]);
      // NaN fails the comparison: a flow that is not finite is not consistent either.
      if (!(gap <= tolerance_px + kShareOfFlow * std::hypot(f[u][0], f[u][1]))) o[u] = 255;
    }
  }
  return out;
}

cv::Mat hiddenIn(const cv::Mat& depth_a, const cv::Mat& depth_b, const CameraIntrinsics& camera,
                 const SE3& T_cam_b_cam_a, double margin) {
  if (depth_a.type() != CV_32FC1 || depth_b.type() != CV_32FC1 || depth_a.size() != depth_b.size() ||
      depth_a.cols != camera.width || depth_a.rows != camera.height)
    throw InputError("hiddenIn: both depths must be CV_32FC1 of the camera's size");
  cv::Mat hidden(depth_a.size(), CV_8U, cv::Scalar(0));
  cv::parallel_for_(cv::Range(0, depth_a.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* z = depth_a.ptr<float>(v);
      uint8_t* h = hidden.ptr<uint8_t>(v);
      for (int u = 0; u < depth_a.cols; ++u) {
        if (!(z[u] > 0) || !std::isfinite(z[u])) continue;
        const Eigen::Vector3d X = T_cam_b_cam_a * camera.backproject(u, v, z[u]);
        if (X.z() <= 0) continue;
        const Eigen::Vector2d p = camera.project(X);
        const int pu = static_cast<int>(std::lround(p.x())), pv = static_cast<int>(std::lround(p.y()));
        if (pu < 0 || pv < 0 || pu >= depth_b.cols || pv >= depth_b.rows) continue;
        const float nearest = smallestDepthAround(depth_b, pu, pv);
        if (nearest > 0 && nearest < X.z() * (1 - margin)) h[u] = 255;
      }
    }
  });
  return hidden;
}

FlowField chainFlows(const std::vector<const FlowField*>& steps) {
  if (steps.empty()) throw InputError("chainFlows: no flow to chain");
  for (const FlowField* f : steps)
    if (!f || f->uv.type() != CV_32FC2 || f->uv.size() != steps.front()->uv.size())
      throw InputError("chainFlows: every step must be a CV_32FC2 flow of one size");
  FlowField chained{steps.front()->uv.clone()};
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat step;
  for (size_t i = 1; i < steps.size(); ++i) {
    // Where the chain has got to; a NaN position is outside, where remap gives NaN.
    cv::remap(steps[i]->uv, step, landingPositions(chained.uv), cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar(nan, nan));
    chained.uv += step;
  }
  return chained;
}

cv::Mat largerResidual(const cv::Mat& r_F, const cv::Mat& other) {
  if (other.empty()) return r_F;
  if (r_F.type() != CV_32FC1 || other.type() != CV_32FC1 || r_F.size() != other.size())
    throw InputError("largerResidual: both residuals must be CV_32FC1 of one size");
  cv::Mat out = r_F.clone();
  for (int v = 0; v < out.rows; ++v) {
    const float* b = other.ptr<float>(v);
    float* o = out.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u)
      if (!std::isnan(o[u]) && !std::isnan(b[u])) o[u] = std::max(o[u], b[u]);
  }
  return out;
}

double finiteMedian(const cv::Mat& values) {
  if (values.type() != CV_32FC1) throw InputError("finiteMedian: values are not CV_32FC1");
  std::vector<float> v;
  v.reserve(values.total());
  for (int r = 0; r < values.rows; ++r) {
    const float* p = values.ptr<float>(r);
    for (int c = 0; c < values.cols; ++c)
      if (std::isfinite(p[c])) v.push_back(p[c]);
  }
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

cv::Mat relativeToFrameError(const cv::Mat& r_F, double typical_px) {
  if (typical_px <= 0 || r_F.empty()) return r_F;
  const double median = finiteMedian(r_F);
  if (!(median > typical_px)) return r_F;
  return r_F * (typical_px / median);
}

}  // namespace ff

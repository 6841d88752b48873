#include "flowfusion/odometry/dense_odometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"

namespace ff {

void validate(const OdometryConfig& c) {
  const auto require = [](bool ok, const std::string& what) {
    if (!ok) throw InputError("odometry." + what);
  };
  // Finite and in (lo, hi].
  const auto within = [](double v, double lo, double hi) { return std::isfinite(v) && v > lo && v <= hi; };
  require(c.levels >= 1 && c.levels <= 8, "levels must be in [1, 8]");
  require(c.finest_level >= 0 && c.finest_level < c.levels, "finest_level must be in [0, levels)");
  require(c.max_iterations >= 1 && c.max_iterations <= 1000 && c.max_iterations_finest >= 1 &&
              c.max_iterations_finest <= 1000,
          "max_iterations and max_iterations_finest must be 1 to 1000");
  require(c.alpha_I >= 0 && std::isfinite(c.alpha_I), "alpha_I must be a finite value >= 0");
  require(within(c.sigma_I, 0, 1e3), "sigma_I must be in (0, 1000]");
  require(within(c.cauchy_c, 0, 1e3), "cauchy_c must be in (0, 1000]");
  require(c.use_intensity || c.use_depth, "use_intensity and use_depth cannot both be false");
  require(within(c.depth_sigma_a, 0, 10) && c.depth_sigma_b >= 0 && c.depth_sigma_b <= 10,
          "depth_sigma_a must be in (0, 10] m and depth_sigma_b in [0, 10] 1/m");
  require(c.depth_slope_sigma >= 0 && c.depth_slope_sigma <= 100, "depth_slope_sigma must be in [0, 100] px");
  require(c.depth_offset_sigma_per_rad >= 0 && c.depth_offset_sigma_per_rad <= 1e3,
          "depth_offset_sigma_per_rad must be in [0, 1000] (1/m per radian; 0 turns the offset off)");
  require(c.depth_offset_dead_zone >= 0 && c.depth_offset_dead_zone <= 1,
          "depth_offset_dead_zone must be in [0, 1] (1/m)");
  require(within(c.min_depth, 0, 100) && within(c.max_depth, c.min_depth, 1000),
          "min_depth must be positive and below max_depth (metres)");
  require(within(c.convergence_eps, 0, 1), "convergence_eps must be in (0, 1]");
  require(c.occlusion_ratio >= 0 && c.occlusion_ratio < 1, "occlusion_ratio must be in [0, 1) (0 turns it off)");
  require(c.min_valid_fraction >= 0 && c.min_valid_fraction < 1, "min_valid_fraction must be in [0, 1)");
  require(within(c.max_translation, 0, 1e3) && within(c.max_rotation_deg, 0, 180),
          "max_translation must be in (0, 1000] m and max_rotation_deg in (0, 180] deg");
}

OdometryFrame prepareOdometryFrame(const cv::Mat& intensity, const cv::Mat& depth, const CameraIntrinsics& camera,
                                   const OdometryConfig& config) {
  OdometryFrame f;
  f.pyramid = buildPyramid(intensity, depth, camera, config.levels, config.finest_level);
  return f;
}

namespace {

// A CV_32F image's pixels (borrowed: the Mat must outlive it) without cv::Mat's out-of-line calls
// (Mat::empty is one in OpenCV 4.6): a call in the per-pixel loops made the compiler spill
// registers and reload every Mat field for each pixel.
struct FloatImage {
  const float* data = nullptr;  // nullptr: no image
  size_t stride = 0;            // floats per row
  FloatImage() = default;
  explicit FloatImage(const cv::Mat& m)
      : data(m.empty() ? nullptr : m.ptr<float>()), stride(m.empty() ? 0 : m.step1()) {}
  const float* row(int y) const { return data + y * stride; }
};

// Bilinear sample of a CV_32F image at (u, v); caller guarantees 0 <= u < cols-1, 0 <= v < rows-1.
inline float bilinear(const FloatImage& m, int x0, int y0, float ax, float ay) {
  const float* r0 = m.row(y0) + x0;
  const float* r1 = m.row(y0 + 1) + x0;
  return (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
}

// Depth at (u, v) when all four neighbours are valid and lie on one surface, else 0.
inline float bilinearDepth(const FloatImage& d, int x0, int y0, float ax, float ay) {
  const float* r0 = d.row(y0) + x0;
  const float* r1 = d.row(y0 + 1) + x0;
  const float a = r0[0], b = r0[1], c = r1[0], e = r1[1];
  const float lo = std::min(std::min(a, b), std::min(c, e));
  const float hi = std::max(std::max(a, b), std::max(c, e));
  if (lo <= 0 || hi > lo * 1.05f) return 0;
  return (1 - ay) * ((1 - ax) * a + ax * b) + ay * ((1 - ax) * c + ax * e);
}

// A target depth z (m, 0 = none) whose inverse depth is moved by `offset` (1/m): 1 / (1/z + offset).
inline float withOffset(float z, float offset) { return z / (1 + offset * z); }

// A target level's images and pixel weights (empty: none) as FloatImages.
struct TargetImages {
  FloatImage depth, intensity, grad_x, grad_y, dgrad_x, dgrad_y, weight;
  TargetImages(const PyramidLevel& B, const cv::Mat& wB)
      : depth(B.depth), intensity(B.intensity), grad_x(B.grad_x), grad_y(B.grad_y), dgrad_x(B.dgrad_x),
        dgrad_y(B.dgrad_y), weight(wB) {}
};

// log(1 + q) for q >= 0 to about 1e-4 relative: the robust cost only decides whether a step
// lowered the cost, and std::log1p took a quarter of the odometry's time.
inline float fastLog1p(float q) {
  const float x = 1.0f + q;
  int32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const int e = ((bits >> 23) & 0xff) - 127;
  bits = (bits & 0x007fffff) | 0x3f800000;  // mantissa m in [1, 2)
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  // log(m) on [1, 2): log((1+s)/(1-s)) = 2 (s + s^3/3 + s^5/5 + s^7/7), s = (m-1)/(m+1) <= 1/3.
  const float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
  return 0.69314718f * e + 2.0f * s * (1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7))));
}

// Parameters of the normal equations: the pose's twist (6), and with the depth offset estimated
// (OdometryConfig::depth_offset_sigma_per_rad) the target's inverse-depth offset as a seventh. The
// per-row sums are instantiated for both: the seventh column costs about 9 % of the odometry.
constexpr int kPoseParams = 6, kOffsetParams = 7;
constexpr int hessianSize(int params) { return params * (params + 1) / 2; }  // upper triangle
constexpr int kLanes = 8;  // partial sums per dot product: whole SIMD registers, so the loops vectorise

// sum_t a[t] b[t] over n (a multiple of kLanes) terms, in kLanes partial sums (a fixed order).
inline float lanesDot(const float* a, const float* b, int n) {
  std::array<float, kLanes> s{};
  for (int t = 0; t < n; t += kLanes)
    for (int l = 0; l < kLanes; ++l) s[l] += a[t + l] * b[t + l];
  return ((s[0] + s[1]) + (s[2] + s[3])) + ((s[4] + s[5]) + (s[6] + s[7]));
}

// The Gauss-Newton terms of one image row, kept column by column (Jacobian J0..J(P-1), residual r,
// pixel weight v), so that the residuals' scales, the IRLS weights, the Cauchy cost and the normal
// equations are computed in loops the compiler vectorises, instead of 27 scalar updates per term.
template <int P>
class RowTerms {
 public:
  RowTerms(int max_terms, float inv_c2, float slope_sigma) : inv_c2_(inv_c2), slope_sigma_(slope_sigma) {
    // Uninitialised (a zeroed set for each of the 16 stripes of every iteration cost 0.3 % of a
    // run's instructions in memset): add() writes the terms, sumInto() zeroes the padding.
    for (auto& col : cols_) col.reset(new float[(max_terms + kLanes - 1) / kLanes * kLanes]);
  }
  // A term whose J and r are final.
  void add(const float J[P], float r, float v) { add(J, r, v, 1.0f, 0.0f); }
  // A depth term whose J and r are still to be divided by sqrt(s2) + sqrt(g2) * slope_sigma
  // (s2: the sum of the two depths' squared sigmas, g2: the squared depth gradient; the final
  // terms above pass 1 and 0, a division by exactly 1).
  void add(const float J[P], float r, float v, float s2, float g2) {
    for (int k = 0; k < P; ++k) cols_[k][n_] = J[k];
    cols_[kR][n_] = r;
    cols_[kV][n_] = v;
    cols_[kS2][n_] = s2;
    cols_[kG2][n_] = g2;
    ++n_;
  }
  // Adds the upper triangle of J^T W J (row by row) and J^T W r with the Cauchy weights
  // w = v / (1 + q), q = r^2 / c^2, summed in float, to H and g, and returns sum v log(1 + q);
  // starts the next row.
  float sumInto(std::array<double, hessianSize(P)>& H, std::array<double, P>& g) {
    scaleDepthTerms();
    const int n = (n_ + kLanes - 1) / kLanes * kLanes;
    for (auto& col : cols_) std::fill(col.get() + n_, col.get() + n, 0.0f);
    const float* v = cols_[kV].get();
    const float* q = cols_[kQ].get();
    float* w = cols_[kW].get();
    float* wJ = cols_[kWJ].get();
    for (int t = 0; t < n; ++t) wJ[t] = fastLog1p(q[t]);
    const float cost = lanesDot(v, wJ, n);
    for (int t = 0; t < n; ++t) w[t] = v[t] / (1 + q[t]);
    int k = 0;
    for (int i = 0; i < P; ++i) {
      const float* Ji = cols_[i].get();
      for (int t = 0; t < n; ++t) wJ[t] = w[t] * Ji[t];
      for (int j = i; j < P; ++j) H[k++] += lanesDot(wJ, cols_[j].get(), n);
      g[i] += lanesDot(wJ, cols_[kR].get(), n);
    }
    n_ = 0;
    return cost;
  }

 private:
  // Divides the depth terms' J and r by their sigma and sets q for all terms.
  void scaleDepthTerms() {
    const float* s2 = cols_[kS2].get();
    const float* g2 = cols_[kG2].get();
    float* inv_s = cols_[kW].get();
    for (int t = 0; t < n_; ++t) inv_s[t] = 1.0f / (std::sqrt(s2[t]) + std::sqrt(g2[t]) * slope_sigma_);
    for (int k = 0; k < P; ++k) {
      float* J = cols_[k].get();
      for (int t = 0; t < n_; ++t) J[t] *= inv_s[t];
    }
    float* r = cols_[kR].get();
    float* q = cols_[kQ].get();
    for (int t = 0; t < n_; ++t) {
      r[t] *= inv_s[t];
      q[t] = r[t] * r[t] * inv_c2_;
    }
  }

  // Columns after the Jacobian's; kW and kWJ: scratch.
  static constexpr int kR = P, kV = kR + 1, kQ = kR + 2, kW = kR + 3, kWJ = kR + 4, kS2 = kR + 5, kG2 = kR + 6;
  std::array<std::unique_ptr<float[]>, kG2 + 1> cols_;
  int n_ = 0;
  float inv_c2_, slope_sigma_;
};

// Normal equations (upper triangle of J^T W J, J^T W r), cost and count. Terms are summed in
// float within one image row and carried over in double, which keeps the inner loop cheap
// without losing precision over hundreds of thousands of pixels.
template <int P>
struct Accumulator {
  std::array<double, hessianSize(P)> H{};
  std::array<double, P> g{};
  double cost = 0;
  int count = 0;

  void merge(const Accumulator& o) {
    for (int i = 0; i < hessianSize(P); ++i) H[i] += o.H[i];
    for (int i = 0; i < P; ++i) g[i] += o.g[i];
    cost += o.cost;
    count += o.count;
  }
  Eigen::Matrix<double, P, P> hessian() const {
    Eigen::Matrix<double, P, P> m;
    int k = 0;
    for (int i = 0; i < P; ++i)
      for (int j = i; j < P; ++j) m(i, j) = m(j, i) = H[k++];
    return m;
  }
};

// Where a reference pixel lands in the current frame, and the values found there.
struct Warp {
  float qx, qy, qz;  // point in the current camera frame, m
  float iz;          // 1 / qz
  float u, v;        // pixel in the current frame
  int x0, y0;
  float ax, ay;
};

// The warps of one image row, column by column (see warpRow).
struct RowWarp {
  std::vector<float> qx, qy, qz, iz, u, v;
  std::vector<int32_t> ok;  // 1 where the pixel takes part
  // Always inlined: the row loops vectorise, and keep their column pointers in registers, only
  // where the compiler sees that the seven columns are distinct allocations.
  [[gnu::always_inline]] explicit RowWarp(int cols)
      : qx(cols), qy(cols), qz(cols), iz(cols), u(cols), v(cols), ok(cols) {}
  Warp at(int x) const {
    Warp w{qx[x], qy[x], qz[x], iz[x], u[x], v[x], static_cast<int>(u[x]), static_cast<int>(v[x]), 0, 0};
    w.ax = w.u - w.x0;
    w.ay = w.v - w.y0;
    return w;
  }
};

// How a row's back-projection scales by the focal lengths: computePixelResiduals divides by fx and
// fy, the odometry's accumulation multiplies by their inverses (last bits differ, so each keeps its
// own arithmetic).
enum class FocalScaling { kDivide, kMultiplyInverse };

// Where the pixels x0 <= x < x1 of row y (depths dA) land in the target, in a loop the compiler
// vectorises: w.q*, w.iz, w.u, w.v of every pixel and whether it takes part (depth in [zmin,
// zmax], in front of the target camera, inside its image); the gathers that follow are scalar.
// Always inlined, like RowWarp's constructor, so the loop sees the columns' allocations.
template <FocalScaling kScaling>
[[gnu::always_inline]] inline void warpRow(const Eigen::Matrix3f& R, const Eigen::Vector3f& t,
                                           const CameraIntrinsics& cam, const float* dA, int y, int x0, int x1,
                                           float zmin, float zmax, RowWarp& rw) {
  // Locals, so that the compiler sees that the stores below do not change them.
  const float r00 = R(0, 0), r01 = R(0, 1), r02 = R(0, 2), r10 = R(1, 0), r11 = R(1, 1), r12 = R(1, 2);
  const float r20 = R(2, 0), r21 = R(2, 1), r22 = R(2, 2), t0 = t.x(), t1 = t.y(), t2 = t.z();
  const float fx = static_cast<float>(cam.fx), fy = static_cast<float>(cam.fy);
  const float cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  const float inv_fx = 1.0f / fx, ny = (y - cy) * (1.0f / fy);
  const float umax = static_cast<float>(cam.width - 1), vmax = static_cast<float>(cam.height - 1);
  float *qxs = rw.qx.data(), *qys = rw.qy.data(), *qzs = rw.qz.data(), *izs = rw.iz.data();
  float *us = rw.u.data(), *vs = rw.v.data();
  int32_t* ok = rw.ok.data();
  for (int x = x0; x < x1; ++x) {
    const float z = dA[x];
    float px, py;
    if constexpr (kScaling == FocalScaling::kDivide) {
      px = (x - cx) * z / fx;
      py = (y - cy) * z / fy;
    } else {
      px = (x - cx) * inv_fx * z;
      py = ny * z;
    }
    const float qx = r00 * px + r01 * py + r02 * z + t0;
    const float qy = r10 * px + r11 * py + r12 * z + t1;
    const float qz = r20 * px + r21 * py + r22 * z + t2;
    const float iz = 1.0f / qz;
    const float u = fx * qx * iz + cx, v = fy * qy * iz + cy;
    qxs[x] = qx;
    qys[x] = qy;
    qzs[x] = qz;
    izs[x] = iz;
    us[x] = u;
    vs[x] = v;
    ok[x] = (z >= zmin) & (z <= zmax) & (qz >= zmin) & (u >= 0) & (v >= 0) & (u < umax) & (v < vmax);
  }
}

// Weights resized to a level's size (nearest, as weights are per-cluster constants).
cv::Mat weightsAtLevel(const cv::Mat& weights, const cv::Size& size) {
  if (weights.empty()) return {};
  CV_Assert(weights.type() == CV_32FC1);
  if (weights.size() == size) return weights;
  cv::Mat out;
  cv::resize(weights, out, size, 0, 0, weights.cols > size.width ? cv::INTER_AREA : cv::INTER_NEAREST);
  return out;
}

// Target weight at the pixel nearest to a warp, 1 without weights.
inline float targetWeight(const FloatImage& weight, const Warp& w) {
  if (!weight.data) return 1.0f;
  return weight.row(w.y0 + (w.ay > 0.5f ? 1 : 0))[w.x0 + (w.ax > 0.5f ? 1 : 0)];
}

// The target's surface at a warp lies in front of the warped point (depth qz) by more than
// `ratio` of its depth: the point is hidden there.
inline bool hiddenInTarget(float zB, float qz, float ratio) { return ratio > 0 && zB > 0 && zB < qz * (1.0f - ratio); }

// d(image value at the warped pixel)/d(xi) for a left perturbation q' = q + dv + dw x q, from the
// image's gradient (gx, gy) per pixel: the chain rule through the projection, written out.
inline void imageJacobian(float gx, float gy, const Warp& w, float fx, float fy, float J[kPoseParams]) {
  const float ga = gx * fx, gb = gy * fy;
  const float X = w.qx * w.iz, Y = w.qy * w.iz;
  J[0] = ga * w.iz;
  J[1] = gb * w.iz;
  J[2] = -(ga * X + gb * Y) * w.iz;
  J[3] = -(ga * X * Y + gb * (1 + Y * Y));
  J[4] = ga * (1 + X * X) + gb * X * Y;
  J[5] = gb * X - ga * Y;
}

// One level's settings and images, in the float form the per-pixel loop uses.
struct LevelTerms {
  const PyramidLevel& A;
  const TargetImages B;
  const FloatImage wimg;
  Eigen::Matrix3f R;
  Eigen::Vector3f t;
  float fx, fy;
  float inv_c2, half_c2, sI;  // Cauchy 1 / c^2 and c^2 / 2; alpha_I / sigma_I
  float sigma_a, sigma_b, slope_sigma;
  float zmin, zmax, occlusion;
  bool use_intensity, use_depth;
  float depth_offset;  // 1/m, added to the target's inverse depths

  LevelTerms(const PyramidLevel& A_, const PyramidLevel& B_, const cv::Mat& wimg_, const cv::Mat& wB_, const SE3& T,
             const OdometryConfig& c, double depth_offset_)
      : A(A_), B(B_, wB_), wimg(wimg_), R(T.rotation().cast<float>()), t(T.translation().cast<float>()),
        fx(static_cast<float>(A_.camera.fx)), fy(static_cast<float>(A_.camera.fy)),
        inv_c2(static_cast<float>(1.0 / (c.cauchy_c * c.cauchy_c))),
        half_c2(static_cast<float>(0.5 * c.cauchy_c * c.cauchy_c)),
        sI(static_cast<float>(c.alpha_I / c.sigma_I)), sigma_a(static_cast<float>(c.depth_sigma_a)),
        sigma_b(static_cast<float>(c.depth_sigma_b)), slope_sigma(static_cast<float>(c.depth_slope_sigma)),
        zmin(static_cast<float>(c.min_depth)), zmax(static_cast<float>(c.max_depth)),
        occlusion(static_cast<float>(c.occlusion_ratio)), use_intensity(c.use_intensity), use_depth(c.use_depth),
        depth_offset(static_cast<float>(depth_offset_)) {}

  float depthSigma(float z) const {
    const float dz = z - 0.4f;
    return sigma_a + sigma_b * dz * dz;
  }

  // The terms of row y: intensity and depth of every source pixel that warps into the target.
  template <int P>
  void row(int y, RowWarp& rw, RowTerms<P>& terms, Accumulator<P>& a) const {
    const float* iA = A.intensity.ptr<float>(y);
    const float* wr = wimg.data ? wimg.row(y) : nullptr;
    const int cols = A.depth.cols;
    warpRow<FocalScaling::kMultiplyInverse>(R, t, A.camera, A.depth.ptr<float>(y), y, 1, cols - 1, zmin, zmax, rw);
    for (int x = 1; x < cols - 1; ++x) {
      if (!rw.ok[x]) continue;
      float v_pix = wr ? wr[x] : 1.0f;
      if (v_pix <= 0) continue;
      const Warp w = rw.at(x);
      v_pix *= targetWeight(B.weight, w);
      if (v_pix <= 0) continue;
      float zB = bilinearDepth(B.depth, w.x0, w.y0, w.ax, w.ay);
      if constexpr (P == kOffsetParams) zB = withOffset(zB, depth_offset);
      if (hiddenInTarget(zB, w.qz, occlusion)) continue;
      bool used = false;
      float J[P];
      if (use_intensity) {
        const float r = (bilinear(B.intensity, w.x0, w.y0, w.ax, w.ay) - iA[x]) * sI;
        imageJacobian(bilinear(B.grad_x, w.x0, w.y0, w.ax, w.ay) * sI, bilinear(B.grad_y, w.x0, w.y0, w.ax, w.ay) * sI,
                      w, fx, fy, J);
        if constexpr (P == kOffsetParams) J[6] = 0;
        terms.add(J, r, v_pix);
        used = true;
      }
      if (use_depth && zB > 0) {
        const float gx = bilinear(B.dgrad_x, w.x0, w.y0, w.ax, w.ay);
        const float gy = bilinear(B.dgrad_y, w.x0, w.y0, w.ax, w.ay);
        const float sA = depthSigma(w.qz), sB = depthSigma(zB);
        imageJacobian(gx, gy, w, fx, fy, J);
        // minus d(q_z)/d(xi) = [0 0 1 | q_y -q_x 0]
        J[2] -= 1;
        J[3] -= w.qy;
        J[4] += w.qx;
        if constexpr (P == kOffsetParams) J[6] = -zB * zB;  // d(zB)/d(offset)
        terms.add(J, zB - w.qz, v_pix, sA * sA + sB * sB, gx * gx + gy * gy);
        used = true;
      }
      if (used) ++a.count;
    }
    a.cost += half_c2 * terms.sumInto(a.H, a.g);
  }
};

constexpr int kStripes = 16;  // fixed so that sums, and results, do not depend on the thread count

// What the Gauss-Newton iterations estimate: the pose and the target's inverse-depth offset.
struct OdometryState {
  SE3 T_target_source;
  double depth_offset = 0;  // 1/m, added to the target's inverse depths
};

// The normal equations of one Gauss-Newton iteration at one level in `state`,
// summed over fixed row stripes so that the result does not depend on the thread count.
template <int P>
Accumulator<P> accumulateLevel(const PyramidLevel& A, const PyramidLevel& B, const cv::Mat& wimg, const cv::Mat& wB,
                               const OdometryState& state, const OdometryConfig& c) {
  const LevelTerms level(A, B, wimg, wB, state.T_target_source, c, state.depth_offset);
  std::array<Accumulator<P>, kStripes> acc{};
  const int rows = A.depth.rows;
  cv::parallel_for_(cv::Range(0, kStripes), [&](const cv::Range& range) {
    RowTerms<P> terms(2 * A.depth.cols, level.inv_c2, level.slope_sigma);
    RowWarp warps(A.depth.cols);
    for (int s = range.start; s < range.end; ++s) {
      const int y_begin = rows * s / kStripes, y_end = rows * (s + 1) / kStripes;
      for (int y = std::max(y_begin, 1); y < std::min(y_end, rows - 1); ++y) level.row(y, warps, terms, acc[s]);
    }
  });
  Accumulator<P> total;
  for (const auto& a : acc) total.merge(a);
  return total;
}

}  // namespace

DenseOdometry::DenseOdometry(const OdometryConfig& config) : config_(config) { validate(config_); }

namespace {

// A Gauss-Newton step and the normal equations it came from.
struct OdometryStep {
  Vector6d pose = Vector6d::Zero();  // twist applied on the left
  double offset = 0;                 // 1/m
  Matrix6d H_pose = Matrix6d::Zero();          // the pose's information (with the offset marginalised)
  Matrix6d H_pose_held = Matrix6d::Zero();     // the pose's information with the offset held
  Vector6d H_pose_offset = Vector6d::Zero();  // the pose's coupling to the offset
};

// One Gauss-Newton step from the normal equations of a level: the pose's (6 parameters), or (7)
// the pose's and the depth offset's, the offset pulled towards 0 by offset_information (the
// prior's weight) and eliminated from the pose's system (Schur complement). Returns false when that
// system is not positive definite or the step not finite.
template <int P>
bool solveStep(const Accumulator<P>& total, double depth_offset, double offset_information, OdometryStep& step) {
  const Eigen::Matrix<double, P, P> H = total.hessian();
  const Eigen::Map<const Eigen::Matrix<double, P, 1>> g(total.g.data());
  step.H_pose = H.template topLeftCorner<6, 6>();
  step.H_pose_held = step.H_pose;
  Vector6d g_pose = g.template head<6>();
  double h_oo = 0, g_o = 0;
  if constexpr (P == kOffsetParams) {
    step.H_pose_offset = H.template topRightCorner<6, 1>();
    h_oo = H(6, 6) + offset_information;
    g_o = g[6] + offset_information * depth_offset;
    step.H_pose -= step.H_pose_offset * step.H_pose_offset.transpose() / h_oo;
    g_pose -= step.H_pose_offset * (g_o / h_oo);
  }
  const Eigen::LDLT<Matrix6d> ldlt(step.H_pose);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  step.pose = ldlt.solve(-g_pose);
  if constexpr (P == kOffsetParams) step.offset = -(g_o + step.H_pose_offset.dot(step.pose)) / h_oo;
  return step.pose.allFinite() && std::isfinite(step.offset);
}

// One Gauss-Newton iteration's sums at a level (valid pixels, mean robust cost) and the step they
// give, with P parameters (see solveStep); solved only where at least 12 pixels take part.
struct LevelStep {
  int count = 0;
  double cost = 0;
  bool solved = false;
  OdometryStep step;
};
template <int P>
LevelStep levelStep(const PyramidLevel& A, const PyramidLevel& B, const cv::Mat& wimg, const cv::Mat& wB,
                    const OdometryState& state, const OdometryConfig& c, double offset_information_per_pixel) {
  const Accumulator<P> total = accumulateLevel<P>(A, B, wimg, wB, state, c);
  LevelStep s{total.count, total.count ? total.cost / total.count : 0.0, false, {}};
  if (total.count >= 12)
    s.solved = solveStep(total, state.depth_offset, offset_information_per_pixel * total.count, s.step);
  return s;
}

// The Gauss-Newton iterations at one pyramid level from `state`, with the depth offset estimated
// (offset_information_per_pixel > 0) or held; counts them, and at the finest level records the valid
// pixels and cost in `result` and the last step's normal equations in `last`.
void iterateLevel(const OdometryConfig& c, const OdometryFrame& source, const OdometryFrame& target, int level,
                  const cv::Mat& source_weights, const cv::Mat& target_weights, double offset_information_per_pixel,
                  OdometryState& state, OdometryResult& result, OdometryStep& last) {
  const PyramidLevel& A = source.level(level);
  const PyramidLevel& B = target.level(level);
  const cv::Mat wimg = weightsAtLevel(source_weights, A.depth.size());
  const cv::Mat wB = weightsAtLevel(target_weights, B.depth.size());
  double prev_cost = std::numeric_limits<double>::infinity();
  OdometryState before_step = state;
  const int iterations = level == c.finest_level ? c.max_iterations_finest : c.max_iterations;
  for (int it = 0; it < iterations; ++it) {
    const LevelStep s = offset_information_per_pixel > 0
                            ? levelStep<kOffsetParams>(A, B, wimg, wB, state, c, offset_information_per_pixel)
                            : levelStep<kPoseParams>(A, B, wimg, wB, state, c, 0.0);
    ++result.iterations;
    if (level == c.finest_level) {
      result.valid_pixels = s.count;
      result.final_cost = s.cost;
    }
    if (s.count < 12) break;
    // A rise in cost means the last step overshot: take it back and refine on the next level.
    if (s.cost > prev_cost * 1.0001) {
      state = before_step;
      break;
    }
    prev_cost = s.cost;
    last = s.step;
    if (!s.solved) break;
    before_step = state;
    state.T_target_source = expSE3(s.step.pose) * state.T_target_source;
    state.depth_offset += s.step.offset;
    if (s.step.pose.norm() < c.convergence_eps) break;
  }
}

// Only the part of the offset beyond the dead zone is taken (a depth rendered from the map is off by
// about 1e-4 1/m at range, which a free offset turns into forward motion); the pose moves to its
// optimum with the offset held there, to first order from the last normal equations:
// -H_pose_held^-1 H_pose_offset (held - estimated).
void holdOffsetBeyondDeadZone(const OdometryConfig& c, const OdometryStep& last, OdometryState& state) {
  const double held =
      std::copysign(std::max(0.0, std::abs(state.depth_offset) - c.depth_offset_dead_zone), state.depth_offset);
  const Eigen::LDLT<Matrix6d> ldlt(last.H_pose_held);
  if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
    const Vector6d xi = ldlt.solve(-last.H_pose_offset * (held - state.depth_offset));
    if (xi.allFinite()) state.T_target_source = expSE3(xi) * state.T_target_source;
  }
  state.depth_offset = held;
}

}  // namespace

double DenseOdometry::offsetInformationPerPixel(const SE3& T_init) const {
  const double sigma = config_.depth_offset_sigma_per_rad * std::abs(logSE3(T_init)[4]);
  return sigma > 0 ? 1.0 / (sigma * sigma) : 0.0;
}

OdometryResult DenseOdometry::estimate(const OdometryFrame& source, const OdometryFrame& target, const SE3& T_init,
                                       const cv::Mat& source_weights, const cv::Mat& target_weights,
                                       int coarsest_level, double target_depth_offset_init) const {
  const OdometryConfig& c = config_;
  OdometryResult result;
  result.T_target_source = T_init;
  if (source.pyramid.size() < static_cast<size_t>(c.levels) || target.pyramid.size() < static_cast<size_t>(c.levels)) {
    result.message = "frames were prepared with fewer pyramid levels than configured";
    return result;
  }
  const double offset_information_per_pixel = c.use_depth ? offsetInformationPerPixel(T_init) : 0.0;
  OdometryState state{T_init, offset_information_per_pixel > 0 ? target_depth_offset_init : 0.0};
  OdometryStep last;
  const int start_level = coarsest_level < 0 ? c.levels - 1 : std::clamp(coarsest_level, c.finest_level, c.levels - 1);
  for (int level = start_level; level >= c.finest_level; --level)
    iterateLevel(c, source, target, level, source_weights, target_weights, offset_information_per_pixel, state, result,
                 last);
  if (offset_information_per_pixel > 0 && c.depth_offset_dead_zone > 0) holdOffsetBeyondDeadZone(c, last, state);
  return finish(result, state.T_target_source, state.depth_offset, last.H_pose, source, T_init);
}

OdometryResult DenseOdometry::finish(OdometryResult result, const SE3& T, double depth_offset, const Matrix6d& H_last,
                                     const OdometryFrame& source, const SE3& T_init) const {
  const OdometryConfig& c = config_;
  result.hessian = H_last;
  const int level_pixels = source.level(c.finest_level).depth.rows * source.level(c.finest_level).depth.cols;
  const auto fail = [&](const std::string& why) {
    result.ok = false;
    result.message = why;
    result.T_target_source = T_init;
    return result;
  };
  if (result.valid_pixels < std::max(12.0, c.min_valid_fraction * level_pixels))
    return fail("tracking failed: " + std::to_string(result.valid_pixels) + " pixels with valid depth overlap (need " +
                std::to_string(static_cast<int>(std::max(12.0, c.min_valid_fraction * level_pixels))) + ")");
  if (!T.matrix().allFinite()) return fail("tracking failed: the solution is not finite");
  const Eigen::SelfAdjointEigenSolver<Matrix6d> es(H_last);
  if (es.eigenvalues()(0) <= 1e-9 * std::max(1.0, es.eigenvalues()(5)))
    return fail("tracking failed: the motion is not constrained (degenerate scene)");
  if (translationNorm(T) > c.max_translation || rotationAngleDeg(T) > c.max_rotation_deg)
    return fail("tracking failed: diverged (" + std::to_string(translationNorm(T)) + " m, " +
                std::to_string(rotationAngleDeg(T)) + " deg in one frame)");
  result.ok = true;
  result.T_target_source = T;
  result.target_depth_offset = depth_offset;
  result.message = "ok";
  return result;
}

namespace {

// A depth image with +inf where it has no depth (not > 0): |inf - qz| never lowers a minimum, so
// nearestDepthResidual needs no test per pixel (the branch on d > 0 was mispredicted often enough
// to take two thirds of computePixelResiduals' time on fr1_rpy).
cv::Mat depthOrInfinity(const cv::Mat& depth) {
  cv::Mat out = depth.clone();
  out.setTo(std::numeric_limits<float>::infinity(), ~(depth > 0));
  return out;
}

// The smallest |z - qz| over the valid depths z of a target level within `window` pixels of the
// 2x2 block at (x0, y0), starting from `residual` (the bilinear one); `depth_or_inf` is the level's
// depthOrInfinity.
// Four partial minima, so that the minimum is not one chain of dependent instructions (a minimum
// does not depend on the order: the same value).
float nearestDepthResidual(const cv::Mat& depth_or_inf, int x0, int y0, float qz, int window, float residual) {
  constexpr int kChains = 4;
  std::array<float, kChains> nearest;
  nearest.fill(residual);
  const int x_begin = std::max(0, x0 - window), x_end = std::min(depth_or_inf.cols - 1, x0 + 1 + window);
  for (int y = std::max(0, y0 - window); y <= std::min(depth_or_inf.rows - 1, y0 + 1 + window); ++y) {
    const float* d = depth_or_inf.ptr<float>(y);
    int x = x_begin;
    for (; x + kChains - 1 <= x_end; x += kChains)
      for (int c = 0; c < kChains; ++c) nearest[c] = std::min(nearest[c], std::abs(d[x + c] - qz));
    for (; x <= x_end; ++x) nearest[0] = std::min(nearest[0], std::abs(d[x] - qz));
  }
  return std::min(std::min(nearest[0], nearest[1]), std::min(nearest[2], nearest[3]));
}

}  // namespace

int depthOffsetPx(const SE3& T_prev_cur, double dt_s, double fx_px, double depth_m, double offset_s, int max_px) {
  if (!(dt_s > 0) || !(depth_m > 0)) return 0;
  const double angle_rad = rotationAngleDeg(T_prev_cur) * M_PI / 180.0;
  const double px_per_s = fx_px * (angle_rad + translationNorm(T_prev_cur) / depth_m) / dt_s;
  return static_cast<int>(std::min<double>(max_px, std::lround(px_per_s * offset_s)));
}

PixelResiduals computePixelResiduals(const OdometryFrame& source, const OdometryFrame& target,
                                     const SE3& T_target_source, int level, const OdometryConfig& c,
                                     const cv::Mat& target_weights, int mover_margin_px, int depth_window_px,
                                     double target_depth_offset) {
  const PyramidLevel& A = source.level(level);
  const PyramidLevel& B = target.level(level);
  cv::Mat wB = weightsAtLevel(target_weights, B.depth.size());
  if (mover_margin_px > 0 && !wB.empty()) {
    // The smallest weight within the margin: a mover's pixels spread over its outline.
    // (Into a new image: wB may share the caller's weights.)
    const int k = 2 * mover_margin_px + 1;
    cv::Mat eroded;
    cv::erode(wB, eroded, cv::Mat::ones(k, k, CV_8U));
    wB = eroded;
  }
  const TargetImages target_images(B, wB);
  const CameraIntrinsics& cam = A.camera;
  PixelResiduals out;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.abs_intensity = cv::Mat(A.depth.size(), CV_32F, cv::Scalar(nan));
  out.abs_depth = cv::Mat(A.depth.size(), CV_32F, cv::Scalar(nan));
  out.on_target_mover = cv::Mat(A.depth.size(), CV_32F, cv::Scalar(0));
  const Eigen::Matrix3f R = T_target_source.rotation().cast<float>();
  const Eigen::Vector3f t = T_target_source.translation().cast<float>();
  const float zmin = static_cast<float>(c.min_depth), zmax = static_cast<float>(c.max_depth);
  const float occlusion = static_cast<float>(c.occlusion_ratio);
  const float offset = static_cast<float>(target_depth_offset);
  const int cols = A.depth.cols;
  const cv::Mat target_depth_or_inf = depth_window_px > 0 ? depthOrInfinity(B.depth) : cv::Mat();
  cv::parallel_for_(cv::Range(0, A.depth.rows), [&](const cv::Range& range) {
    RowWarp warps(cols);
    for (int y = range.start; y < range.end; ++y) {
      const float* iA = A.intensity.ptr<float>(y);
      float* oI = out.abs_intensity.ptr<float>(y);
      float* oD = out.abs_depth.ptr<float>(y);
      float* oM = out.on_target_mover.ptr<float>(y);
      warpRow<FocalScaling::kDivide>(R, t, cam, A.depth.ptr<float>(y), y, 0, cols, zmin, zmax, warps);
      for (int x = 0; x < cols; ++x) {
        if (!warps.ok[x]) continue;
        const Warp w = warps.at(x);
        const float zB = withOffset(bilinearDepth(target_images.depth, w.x0, w.y0, w.ax, w.ay), offset);
        if (hiddenInTarget(zB, w.qz, occlusion)) continue;
        if (targetWeight(target_images.weight, w) < 0.5f) {
          oM[x] = 1.f;
          continue;
        }
        oI[x] = std::abs(bilinear(target_images.intensity, w.x0, w.y0, w.ax, w.ay) - iA[x]);
        if (zB > 0) {
          oD[x] = std::abs(zB - w.qz);
          if (depth_window_px > 0)
            oD[x] = nearestDepthResidual(target_depth_or_inf, w.x0, w.y0, w.qz, depth_window_px, oD[x]);
        }
      }
    }
  });
  return out;
}

}  // namespace ff

#include "flowfusion/flow/flow_motion.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>

#include "flowfusion/core/error.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/flow/p3p.h"

namespace ff {

void validate(const ConsensusConfig& c) {
  if (c.grid_step < 1) throw InputError("consensus.grid_step must be at least 1 (pixels)");
  if (!(c.inlier_px > 0)) throw InputError("consensus.inlier_px must be > 0 (pixels)");
  if (c.ransac_iterations < 1) throw InputError("consensus.ransac_iterations must be at least 1");
  if (c.local_hypotheses < 0) throw InputError("consensus.local_hypotheses must be at least 0");
  if (!(c.min_mover_share > 0 && c.min_mover_share < 1))
    throw InputError("consensus.min_mover_share must be in (0, 1)");
  if (!(c.min_captured > 0 && c.min_captured <= 1)) throw InputError("consensus.min_captured must be in (0, 1]");
  if (!(c.min_gain >= 0 && c.min_gain <= 1)) throw InputError("consensus.min_gain must be in [0, 1]");
  if (!(c.map_role_margin > 0 && c.map_role_margin <= 1))
    throw InputError("consensus.map_role_margin must be in (0, 1]");
  if (!(c.nearer_mover_depth_ratio >= 0 && c.nearer_mover_depth_ratio < 1))
    throw InputError("consensus.nearer_mover_depth_ratio must be in [0, 1) (0: the roles by size alone)");
  if (!(c.start_min_separation >= 0 && std::isfinite(c.start_min_separation)))
    throw InputError("consensus.start_min_separation must be a finite share >= 0 of the image motion");
  if (!(c.start_max_black_share >= 0 && c.start_max_black_share <= 1))
    throw InputError("consensus.start_max_black_share must be a share in [0, 1]");
  if (!(c.start_min_texture >= 0 && std::isfinite(c.start_min_texture)))
    throw InputError("consensus.start_min_texture must be a finite number of grey levels per pixel >= 0 (0: all samples)");
}

double textureAt(const cv::Mat& intensity, int u, int v) {
  constexpr int kHalf = 4;  // 9 x 9 pixels
  double xx = 0, yy = 0, xy = 0;
  int n = 0;
  for (int y = std::max(1, v - kHalf); y <= std::min(intensity.rows - 2, v + kHalf); ++y) {
    const float* row = intensity.ptr<float>(y);
    const float* up = intensity.ptr<float>(y - 1);
    const float* down = intensity.ptr<float>(y + 1);
    for (int x = std::max(1, u - kHalf); x <= std::min(intensity.cols - 2, u + kHalf); ++x, ++n) {
      const double gx = 0.5 * (row[x + 1] - row[x - 1]), gy = 0.5 * (down[x] - up[x]);
      xx += gx * gx;
      yy += gy * gy;
      xy += gx * gy;
    }
  }
  if (n == 0) return 0;
  const double smaller = 0.5 * (xx + yy - std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy)) / n;
  return 255.0 * std::sqrt(std::max(smaller, 0.0));
}

FlowCorrespondences sampleFlowCorrespondences(const FlowField& flow, const cv::Mat& depth_a,
                                              const CameraIntrinsics& camera, int step, const cv::Mat& intensity_a,
                                              double min_texture_grey) {
  if (flow.uv.type() != CV_32FC2 || depth_a.type() != CV_32FC1 || flow.uv.size() != depth_a.size() ||
      depth_a.cols != camera.width || depth_a.rows != camera.height)
    throw InputError("sampleFlowCorrespondences: flow (CV_32FC2), depth (CV_32F) and camera sizes must match");
  const bool texture = min_texture_grey > 0 && !intensity_a.empty();
  if (texture && (intensity_a.type() != CV_32FC1 || intensity_a.size() != depth_a.size()))
    throw InputError("sampleFlowCorrespondences: the intensity must be CV_32F of the depth's size");
  FlowCorrespondences c;
  for (int v = step / 2; v < depth_a.rows; v += step)
    for (int u = step / 2; u < depth_a.cols; u += step) {
      const float z = depth_a.at<float>(v, u);
      const cv::Vec2f f = flow.uv.at<cv::Vec2f>(v, u);
      if (!(z > 0) || !std::isfinite(f[0]) || !std::isfinite(f[1])) continue;
      const double ub = u + f[0], vb = v + f[1];
      if (!camera.inImage(ub, vb)) continue;
      const Eigen::Vector3d p = camera.backproject(u, v, z);
      c.points_a.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
      c.pixels_b.emplace_back(static_cast<float>(ub), static_cast<float>(vb));
      if (texture) c.textured.push_back(textureAt(intensity_a, u, v) >= min_texture_grey);
    }
  return c;
}

namespace {

// Squared pixel distance between where T_b_a takes correspondence i's point and its flow target
// (infinite behind the camera).
double squaredError(const FlowCorrespondences& c, size_t i, const CameraIntrinsics& camera, const SE3& T_b_a) {
  const cv::Point3f& p = c.points_a[i];
  const Eigen::Vector3d q = T_b_a * Eigen::Vector3d(p.x, p.y, p.z);
  if (q.z() <= 0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d uv = camera.project(q);
  const double du = uv.x() - c.pixels_b[i].x, dv = uv.y() - c.pixels_b[i].y;
  return du * du + dv * dv;
}

// Whether T_b_a takes correspondence i's point within sqrt(r2) pixels of its flow target.
bool explains(const FlowCorrespondences& c, size_t i, const CameraIntrinsics& camera, const SE3& T_b_a, double r2) {
  return squaredError(c, i, camera, T_b_a) < r2;
}

// The squared reprojection errors of `subset` under T (points behind the camera left out) and,
// when H and g are given, the Gauss-Newton normal equations of a left increment exp(xi) * T.
double reprojectionCost(const FlowCorrespondences& c, const std::vector<int>& subset, const CameraIntrinsics& camera,
                        const SE3& T, Matrix6d* H = nullptr, Vector6d* g = nullptr) {
  double cost = 0;
  if (H) H->setZero();
  if (g) g->setZero();
  for (const int i : subset) {
    const cv::Point3f& p = c.points_a[i];
    const Eigen::Vector3d q = T * Eigen::Vector3d(p.x, p.y, p.z);
    if (!(q.z() > 0)) continue;
    const double iz = 1 / q.z();
    const Eigen::Vector2d r(camera.fx * q.x() * iz + camera.cx - c.pixels_b[i].x,
                            camera.fy * q.y() * iz + camera.cy - c.pixels_b[i].y);
    cost += r.squaredNorm();
    if (!H) continue;
    Eigen::Matrix<double, 2, 3> dproj;
    dproj << camera.fx * iz, 0, -camera.fx * q.x() * iz * iz, 0, camera.fy * iz, -camera.fy * q.y() * iz * iz;
    Eigen::Matrix<double, 3, 6> dq;
    dq << Eigen::Matrix3d::Identity(), -skew(q);
    const Eigen::Matrix<double, 2, 6> J = dproj * dq;
    H->noalias() += J.transpose() * J;
    *g += J.transpose() * r;
  }
  return cost;
}

// T refined by Levenberg-Marquardt on the correspondences `subset` (unchanged with fewer than 6):
// at most 10 steps, until a step moves less than 1e-6 (radians, metres).
SE3 refineOn(const FlowCorrespondences& c, const std::vector<int>& subset, const CameraIntrinsics& camera, const SE3& T) {
  constexpr size_t kMinPoints = 6;
  if (subset.size() < kMinPoints) return T;
  SE3 best = T;
  Matrix6d H;
  Vector6d g;
  double cost = reprojectionCost(c, subset, camera, best, &H, &g);
  double lambda = 1e-3;
  for (int it = 0; it < 10; ++it) {
    Matrix6d A = H;
    A.diagonal() *= 1 + lambda;
    const Vector6d xi = A.ldlt().solve(-g);
    if (!xi.allFinite()) break;
    const SE3 next = orthonormalized(expSE3(xi) * best);
    const double next_cost = reprojectionCost(c, subset, camera, next);
    if (next_cost < cost) {
      best = next;
      cost = reprojectionCost(c, subset, camera, best, &H, &g);
      lambda = std::max(lambda / 10, 1e-9);
    } else {
      lambda *= 10;
    }
    if (xi.lpNorm<Eigen::Infinity>() < 1e-6) break;
  }
  return best;
}

// Motions from four correspondences each (P3P on three, the fourth choosing; p3p.h): `global`
// drawn anywhere, `local` within one image neighbourhood (a fifth of the image width).
std::vector<SE3> drawHypotheses(const FlowCorrespondences& c, const CameraIntrinsics& camera, int global, int local) {
  std::mt19937 rng(20201);  // fixed: the same flow gives the same split
  std::uniform_int_distribution<size_t> pick(0, c.size() - 1);
  const double radius2 = std::pow(camera.width / 5.0, 2);
  std::vector<SE3> out;
  for (int h = 0; h < global + local; ++h) {
    std::vector<size_t> idx{pick(rng)};
    const cv::Point3f& p0 = c.points_a[idx[0]];
    const Eigen::Vector2d uv0 = camera.project(Eigen::Vector3d(p0.x, p0.y, p0.z));
    for (int tries = 0; idx.size() < 4 && tries < 200; ++tries) {
      const size_t j = pick(rng);
      if (std::find(idx.begin(), idx.end(), j) != idx.end()) continue;
      const cv::Point3f& p = c.points_a[j];
      if (h >= global && (camera.project(Eigen::Vector3d(p.x, p.y, p.z)) - uv0).squaredNorm() > radius2) continue;
      idx.push_back(j);
    }
    if (idx.size() < 4) continue;
    std::array<Eigen::Vector3d, 4> points;
    std::array<Eigen::Vector2d, 4> pixels;
    for (size_t k = 0; k < 4; ++k) {
      const cv::Point3f& p = c.points_a[idx[k]];
      points[k] = Eigen::Vector3d(p.x, p.y, p.z);
      pixels[k] = Eigen::Vector2d(c.pixels_b[idx[k]].x, c.pixels_b[idx[k]].y);
    }
    if (const std::optional<SE3> T_b_a = solveP3PChoosingByFourth(points, pixels, camera)) out.push_back(*T_b_a);
  }
  return out;
}

// Which correspondences each motion explains within inlier_px, one bit each.
using InlierBits = std::vector<std::uint64_t>;
InlierBits inlierBits(const FlowCorrespondences& c, const CameraIntrinsics& camera, const SE3& T, double inlier_px) {
  InlierBits bits((c.size() + 63) / 64, 0);
  for (size_t i = 0; i < c.size(); ++i)
    if (explains(c, i, camera, T, inlier_px * inlier_px)) bits[i / 64] |= std::uint64_t{1} << (i % 64);
  return bits;
}

// The indices (i, j) of the two motions that explain the most correspondences one of them alone:
// a far background both a correct and a slightly wrong camera motion explain does not make a pair
// of them look like two motions. A pair explains at most its two inlier counts together: pairs
// that cannot beat the best so far are not counted (the same pair as counting all).
std::pair<int, int> bestPair(const std::vector<InlierBits>& bits) {
  std::vector<int> inliers;
  for (const InlierBits& b : bits) {
    int n = 0;
    for (const std::uint64_t w : b) n += std::popcount(w);
    inliers.push_back(n);
  }
  const int most = *std::max_element(inliers.begin(), inliers.end());
  std::pair<int, int> best{-1, -1};
  int best_cover = -1;
  for (size_t i = 0; i < bits.size(); ++i) {
    if (inliers[i] + most <= best_cover) continue;
    for (size_t j = i + 1; j < bits.size(); ++j) {
      if (inliers[i] + inliers[j] <= best_cover) continue;
      int cover = 0;
      for (size_t w = 0; w < bits[i].size(); ++w) cover += std::popcount(bits[i][w] ^ bits[j][w]);
      if (cover > best_cover) {
        best_cover = cover;
        best = {static_cast<int>(i), static_cast<int>(j)};
      }
    }
  }
  return best;
}

// The split of the two motions given their roles.
FlowMotionSplit withRoles(const FlowCorrespondences& c, const CameraIntrinsics& camera, const ConsensusConfig& config,
                          const SE3& T_b_a_background, const SE3& T_b_a_mover) {
  FlowMotionSplit split;
  split.T_b_a_background = T_b_a_background;
  split.T_b_a_mover = T_b_a_mover;
  const double r2 = config.inlier_px * config.inlier_px;
  split.group.assign(c.size(), FlowMotionSplit::kNeither);
  for (size_t k = 0; k < c.size(); ++k) {
    const double e_bg = squaredError(c, k, camera, T_b_a_background), e_mv = squaredError(c, k, camera, T_b_a_mover);
    if (std::min(e_bg, e_mv) <= 4 * r2) split.group[k] = e_bg <= e_mv ? FlowMotionSplit::kBackground : FlowMotionSplit::kMover;
    if (e_mv < r2 && e_bg > 9 * r2) split.mover_only.push_back(static_cast<int>(k));
  }
  split.ok = true;
  return split;
}

// How many correspondences are in `group`.
std::ptrdiff_t groupSize(const FlowMotionSplit& split, FlowMotionSplit::Group group) {
  return std::count(split.group.begin(), split.group.end(), group);
}

// Whether the mover group outnumbers the background group: in textured samples when the
// correspondences say which are and at least kMinTextured of the two groups' are, else in all.
bool moverGroupIsLarger(const FlowMotionSplit& split, const FlowCorrespondences& c) {
  constexpr std::ptrdiff_t kMinTextured = 30;
  std::ptrdiff_t all[2] = {0, 0}, textured[2] = {0, 0};
  for (size_t k = 0; k < split.group.size(); ++k) {
    const int g = split.group[k];
    if (g == FlowMotionSplit::kNeither) continue;
    ++all[g];
    textured[g] += k < c.textured.size() && c.textured[k];
  }
  const std::ptrdiff_t* count = textured[0] + textured[1] >= kMinTextured ? textured : all;
  return count[FlowMotionSplit::kMover] > count[FlowMotionSplit::kBackground];
}

// The correspondences in `group`.
std::vector<int> membersOf(const FlowMotionSplit& split, FlowMotionSplit::Group group) {
  std::vector<int> members;
  for (size_t k = 0; k < split.group.size(); ++k)
    if (split.group[k] == group) members.push_back(static_cast<int>(k));
  return members;
}

// Whether the map relations make the mover group of `split` the background: its points lay in
// front of the map clearly less often than the background group's. Groups with map relations for
// fewer than a third of their points (or kMinKnown) do not decide.
bool mapSwapsRoles(const FlowMotionSplit& split, const std::vector<MapRelation>& relation, double margin) {
  if (relation.size() != split.group.size()) return false;
  constexpr int kMinKnown = 10;
  int count[2] = {0, 0}, known[2] = {0, 0}, front[2] = {0, 0};
  for (size_t k = 0; k < split.group.size(); ++k) {
    const int g = split.group[k];
    if (g == FlowMotionSplit::kNeither) continue;
    ++count[g];
    known[g] += relation[k] != MapRelation::kUnknown;
    front[g] += relation[k] == MapRelation::kInFront;
  }
  double front_share[2];
  for (int g = 0; g < 2; ++g) {
    if (known[g] < kMinKnown || 3 * known[g] < count[g]) return false;
    front_share[g] = static_cast<double>(front[g]) / known[g];
  }
  return front_share[FlowMotionSplit::kBackground] - front_share[FlowMotionSplit::kMover] >= margin;
}

// Whether the background group (the larger) lies nearer than `ratio` of the mover group's depth
// while the mover group is comparable in size: then the nearer group is the mover.
bool nearerGroupIsMover(const FlowMotionSplit& split, const FlowCorrespondences& c, double ratio) {
  constexpr size_t kMinSamples = 10;
  std::vector<double> z[2];
  for (size_t k = 0; k < split.group.size() && k < c.size(); ++k)
    if (split.group[k] != FlowMotionSplit::kNeither) z[split.group[k]].push_back(c.points_a[k].z);
  const std::vector<double>& background = z[FlowMotionSplit::kBackground];
  const std::vector<double>& mover = z[FlowMotionSplit::kMover];
  if (mover.size() < kMinSamples || mover.size() < kComparableGroups * background.size()) return false;
  return median(background) < ratio * median(mover);
}

}  // namespace

int countFlowInliers(const FlowCorrespondences& c, const CameraIntrinsics& camera, const SE3& T_b_a,
                     double inlier_px) {
  int n = 0;
  for (size_t i = 0; i < c.size(); ++i) n += explains(c, i, camera, T_b_a, inlier_px * inlier_px);
  return n;
}

FlowMotionSplit splitFlowMotions(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                                 const ConsensusConfig& config, const std::vector<SE3>& seeds,
                                 const std::vector<MapRelation>& relation) {
  // Fewer samples than this say nothing about which motions the view holds.
  constexpr size_t kMinSamples = 30;
  if (c.size() < kMinSamples) return {};
  std::vector<SE3> motions = seeds;
  for (const SE3& T : drawHypotheses(c, camera, config.ransac_iterations, config.local_hypotheses))
    motions.push_back(T);
  if (motions.size() < 2) return {};
  std::vector<InlierBits> bits;
  for (const SE3& T : motions) bits.push_back(inlierBits(c, camera, T, config.inlier_px));
  const auto [i, j] = bestPair(bits);
  SE3 T_first = motions[i], T_second = motions[j];
  // Each sample goes to the motion that explains it better (withRoles' groups), each motion is
  // re-fitted on its samples.
  constexpr int kRefinements = 3;
  for (int round = 0; round < kRefinements; ++round) {
    const FlowMotionSplit s = withRoles(c, camera, config, T_first, T_second);
    T_first = refineOn(c, membersOf(s, FlowMotionSplit::kBackground), camera, T_first);
    T_second = refineOn(c, membersOf(s, FlowMotionSplit::kMover), camera, T_second);
  }
  // The background's is the motion of the larger group (by its textured samples where they were
  // told), or of the farther of two comparable ones, unless the map says otherwise.
  FlowMotionSplit split = withRoles(c, camera, config, T_first, T_second);
  if (moverGroupIsLarger(split, c))
    split = withRoles(c, camera, config, T_second, T_first);
  if (nearerGroupIsMover(split, c, config.nearer_mover_depth_ratio))
    split = withRoles(c, camera, config, split.T_b_a_mover, split.T_b_a_background);
  if (mapSwapsRoles(split, relation, config.map_role_margin))
    split = withRoles(c, camera, config, split.T_b_a_mover, split.T_b_a_background);
  return split;
}

std::optional<FlowMotionSplit> splitFlowAgainst(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                                                const SE3& T_b_a_odometry, const ConsensusConfig& config,
                                                const std::vector<MapRelation>& relation) {
  const double off_odometry = static_cast<double>(c.size()) - countFlowInliers(c, camera, T_b_a_odometry, config.inlier_px);
  if (off_odometry < config.min_mover_share * static_cast<double>(c.size())) return std::nullopt;
  FlowMotionSplit split = splitFlowMotions(c, camera, config, {T_b_a_odometry}, relation);
  if (!split.ok) return std::nullopt;
  return split;
}

bool showsMover(const FlowMotionSplit& split, const FlowCorrespondences& c, const ConsensusConfig& config) {
  return static_cast<double>(split.mover_only.size()) >= config.min_mover_share * static_cast<double>(c.size());
}

double moverSeparationShare(const FlowMotionSplit& split, const FlowCorrespondences& c, const CameraIntrinsics& camera) {
  std::vector<double> image_motion, separation;
  for (size_t k = 0; k < c.size() && k < split.group.size(); ++k) {
    image_motion.push_back(std::sqrt(squaredError(c, k, camera, SE3::Identity())));  // the sample's flow
    if (split.group[k] != FlowMotionSplit::kMover) continue;
    const Eigen::Vector3d X(c.points_a[k].x, c.points_a[k].y, c.points_a[k].z);
    const double d = (camera.project(split.T_b_a_mover * X) - camera.project(split.T_b_a_background * X)).norm();
    if (std::isfinite(d)) separation.push_back(d);  // not where a motion puts the point behind the camera
  }
  if (separation.empty()) return 0.0;
  const double motion_px = median(image_motion);
  constexpr double kStill_px = 1e-3;  // below this the image stands still (float rounding of a zero flow)
  return motion_px > kStill_px ? median(separation) / motion_px : std::numeric_limits<double>::infinity();
}

double samplesShareWhere(const FlowCorrespondences& c, const CameraIntrinsics& camera, const cv::Mat& where_a,
                         const FlowMotionSplit* mover_group_of) {
  if (where_a.type() != CV_8UC1 || where_a.cols != camera.width || where_a.rows != camera.height)
    throw InputError("samplesShareWhere: the mask must be CV_8U at the camera's size");
  size_t counted = 0, there = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    if (mover_group_of &&
        (k >= mover_group_of->group.size() || mover_group_of->group[k] != FlowMotionSplit::kMover))
      continue;
    ++counted;
    const Eigen::Vector2d uv = camera.project(Eigen::Vector3d(c.points_a[k].x, c.points_a[k].y, c.points_a[k].z));
    const int u = std::clamp(static_cast<int>(std::lround(uv.x())), 0, where_a.cols - 1);
    const int v = std::clamp(static_cast<int>(std::lround(uv.y())), 0, where_a.rows - 1);
    if (where_a.at<uchar>(v, u)) ++there;
  }
  return counted ? static_cast<double>(there) / static_cast<double>(counted) : 0.0;
}

bool showsMoverGroup(const FlowMotionSplit& split, const FlowCorrespondences& c, const CameraIntrinsics& camera,
                     const ConsensusConfig& config, const cv::Mat& intensity_a) {
  if (split.group.empty() || static_cast<double>(groupSize(split, FlowMotionSplit::kMover)) <
                                 config.min_mover_share * static_cast<double>(split.group.size()))
    return false;
  if (moverSeparationShare(split, c, camera) < config.start_min_separation) return false;
  if (intensity_a.empty() || config.start_max_black_share >= 1) return true;
  const cv::Mat black = intensity_a < kBlackGrey;
  if (samplesShareWhere(c, camera, black) >= kMostlyBlackFrame) return true;
  return samplesShareWhere(c, camera, black, &split) <= config.start_max_black_share;
}

bool misledOdometry(const FlowCorrespondences& c, const CameraIntrinsics& camera, const FlowMotionSplit& split,
                    const SE3& T_b_a_odometry, const ConsensusConfig& config, const std::vector<MapRelation>& relation) {
  const double loose_px = 2 * config.inlier_px;
  const double n = static_cast<double>(c.size());
  if (countFlowInliers(c, camera, split.T_b_a_background, loose_px) >=
      countFlowInliers(c, camera, T_b_a_odometry, loose_px) + config.min_gain * n)
    return true;
  if (!showsMover(split, c, config)) return false;
  // Samples on the static map are no evidence of a capture: an odometry that explains them is right.
  int captured = 0, evidence = 0;
  for (const int k : split.mover_only) {
    if (!relation.empty() && relation[k] == MapRelation::kOnMap) continue;
    ++evidence;
    captured += explains(c, k, camera, T_b_a_odometry, loose_px * loose_px);
  }
  return evidence > 0 && captured >= config.min_captured * static_cast<double>(evidence);
}

}  // namespace ff

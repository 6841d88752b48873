#pragma once
// The rigid motions in the optical flow: the camera's (the background's) and a mover's, found from
// flow correspondences with the current frame's depth (RANSAC over PnP).
//
// Why: dense robust odometry converges to whatever motion its starting point and weights favour.
// When a large near object moves before anything is known of it (the first frames, an object
// walking into view), the odometry can lock onto the object, or, under fast rotation, settle part
// way between the object and a far background that cannot pin the translation down; every later
// stage then scores against a wrong motion and the carried scores keep the error going. A split
// of the flow into two rigid motions does not depend on the odometry: where the odometry's motion
// explains the flow that only the mover's motion explains, the odometry was captured and is
// restarted from the background's motion with the mover marked (pipeline/segmentation_loop.h).
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/flow/optical_flow.h"

namespace ff {

// The defaults and the measurements behind them: docs/tuning.md#consensus.
struct ConsensusConfig {
  bool enabled = true;
  int grid_step = 16;           // px: flow correspondences sampled on this grid of the input image
  // px: reprojection error of a correspondence a motion explains, in the split of the flow into
  // two motions (tight: the flow of the colour images fits its own motions within a pixel).
  double inlier_px = 1.5;
  // Minimal-sample (P3P) motion hypotheses searched for the pair: drawn anywhere in the image (as
  // RANSAC draws them) and drawn within one image neighbourhood (so that they lie on one object).
  int ransac_iterations = 100;
  int local_hypotheses = 100;
  // The mover counts when this share of the samples is explained by its motion within inlier_px
  // and left by the background's beyond 3 inlier_px.
  double min_mover_share = 0.07;
  // The odometry was captured by the mover when its motion explains at least this share of the
  // mover's samples within 2 inlier_px (a correct odometry leaves them: they are 3 inlier_px off
  // the background's motion; the allowance covers colour-depth time offsets).
  double min_captured = 0.3;
  // Or restart when the background's motion explains at least this share of the samples more
  // than the odometry's, within 2 inlier_px (an odometry plainly wrong, mover or not).
  double min_gain = 0.3;
  // The larger group is the mover's when the share of its points that lay in front of the static
  // map in frame B exceeds the other group's by this (a mover filling most of the view); else the
  // larger group is the background.
  double map_role_margin = 0.5;
  // Before that, where the larger group lies nearer than this ratio of the other's depth (medians)
  // and the other holds at least kComparableGroups of its samples, the larger is the mover's: a
  // mover occludes the world behind it (a box over half the view at the start, when the map is
  // the first frame, box and all; docs/tuning.md#nearer_mover_depth_ratio). 0 = by size alone.
  double nearer_mover_depth_ratio = 0.75;
  // For map_role_margin's relations, a point the previous frame's scores held for a mover counts
  // as in front of the map whatever the map shows there: the map never took it, and behind a large
  // mover the map may hold nothing yet (a box over half the view since the first frame), which left
  // the roles to the size alone (docs/tuning.md#previous_movers_in_front). false = the map's depth.
  bool previous_movers_in_front = true;
  // At the start (no scores yet) the split's mover group is taken for the movers only when its
  // motion moves its samples at least this share of the image motion (median flow) away from where
  // the background's motion puts them: the flow's errors that grow with the image motion (blur, the
  // colour-depth offset, rolling shutter) make a second motion within that share under fast
  // rotation (docs/tuning.md#start_min_separation). 0 = any.
  double start_min_separation = 0.15;
  // And only when at most this share of its samples lie on black pixels (grey below kBlackGrey): a
  // black screen's flow follows its reflections and what the flow fills in from around it, a second
  // motion no mover makes (docs/tuning.md#start_max_black_share). 1 = any.
  double start_max_black_share = 0.6;
  // Grey levels (of 255) per pixel (our extension; 0 = by all samples): at the start the larger
  // group is counted over the samples where the image varies at least this much in its weaker
  // direction (textureAt), when 30 or more do: on a uniform surface the flow is filled in from its
  // outline, and a large uniform box near the camera outnumbered the world's measured samples
  // (docs/tuning.md#start_min_texture). After the start the previous frame's movers and the map
  // hold the roles.
  double start_min_texture = 0.8;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(ConsensusConfig, enabled, grid_step, inlier_px, ransac_iterations,
                                                local_hypotheses, min_mover_share, min_captured, min_gain,
                                                map_role_margin, nearer_mover_depth_ratio, previous_movers_in_front,
                                                start_min_separation, start_max_black_share, start_min_texture)

// The smaller group's samples over the larger's at which nearer_mover_depth_ratio applies.
constexpr double kComparableGroups = 0.6;

// When at least this share of all the samples is black, the image is dim rather than a screen
// in a lit room, and start_max_black_share is not applied.
constexpr double kMostlyBlackFrame = 0.5;
// Throws InputError naming the first bad setting.
void validate(const ConsensusConfig& config);

// 3D points of frame A (camera frame, metres) and where the flow takes their pixels in B.
struct FlowCorrespondences {
  std::vector<cv::Point3f> points_a;
  std::vector<cv::Point2f> pixels_b;
  // Per correspondence, whether A's image is textured there (textureAt at least the sampling's
  // min_texture_grey): the flow is measured, not filled in. Empty when not sampled with an image.
  std::vector<unsigned char> textured;
  size_t size() const { return points_a.size(); }
};

// Samples pixels of A on a grid of `step` pixels where A's depth is valid and the flow lands
// inside B. flow.uv and depth_a (CV_32F, metres, <= 0 invalid) have the camera's size. With
// intensity_a (A's grey levels, CV_32F in [0, 1], the same size) and min_texture_grey > 0, also
// which samples are textured.
FlowCorrespondences sampleFlowCorrespondences(const FlowField& flow, const cv::Mat& depth_a,
                                              const CameraIntrinsics& camera, int step,
                                              const cv::Mat& intensity_a = cv::Mat(), double min_texture_grey = 0);

// How much the image (CV_32F grey in [0, 1]) varies around (u, v) in its weaker direction, grey
// levels of 255 per pixel: the square root of the smaller eigenvalue of the structure tensor of
// its central-difference gradients over 9 x 9 pixels. Near 0 on a uniform surface and along a
// single edge, where the optical flow is not determined by the image (the aperture problem).
double textureAt(const cv::Mat& intensity, int u, int v);

// Where a correspondence's point lay in frame B against the static map (rendered at B's pose): on
// its surface, in front of it (something not in the map: a mover, or a point B's scores held for
// one), or unknown (no map there).
enum class MapRelation : unsigned char { kUnknown, kOnMap, kInFront };

// Correspondences T_b_a explains within `inlier_px`, the reprojection error in B.
int countFlowInliers(const FlowCorrespondences& c, const CameraIntrinsics& camera, const SE3& T_b_a,
                     double inlier_px);

// Two motions that together explain the flow: the background's (taken as the camera's: the larger
// group, unless the map relations say its points lay in front of the map) and a mover's. Per
// correspondence, `group` says which explains it (kNeither when neither does within 2 inlier_px).
struct FlowMotionSplit {
  enum Group : unsigned char { kBackground = 0, kMover = 1, kNeither = 2 };
  bool ok = false;  // false: too few correspondences or no pair found
  SE3 T_b_a_background = SE3::Identity();
  SE3 T_b_a_mover = SE3::Identity();
  std::vector<unsigned char> group;
  // Correspondences the mover explains within inlier_px and the background leaves beyond
  // 3 inlier_px: the mover's own evidence.
  std::vector<int> mover_only;
};

// The pair among `seeds` and the minimal-sample hypotheses that explains the most correspondences
// with one motion of the two alone within inlier_px (a far background that a correct and a
// slightly wrong camera motion both explain does not make them a pair), then refined by
// alternately assigning each correspondence to the motion that explains it better and re-fitting
// both (Levenberg-Marquardt). The larger group is the background, or the farther of two comparable
// ones (ConsensusConfig::nearer_mover_depth_ratio); `relation` (one per correspondence, or empty)
// then decides the roles as ConsensusConfig::map_role_margin says. Deterministic.
FlowMotionSplit splitFlowMotions(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                                 const ConsensusConfig& config, const std::vector<SE3>& seeds = {},
                                 const std::vector<MapRelation>& relation = {});

// The split of the sampled flow, seeded with the odometry's motion; none when that motion explains
// all but min_mover_share of the samples within inlier_px (nothing else to find).
std::optional<FlowMotionSplit> splitFlowAgainst(const FlowCorrespondences& c, const CameraIntrinsics& camera,
                                                const SE3& T_b_a_odometry, const ConsensusConfig& config,
                                                const std::vector<MapRelation>& relation = {});

// Whether the split shows a mover: at least min_mover_share of the samples are the mover's own.
bool showsMover(const FlowMotionSplit& split, const FlowCorrespondences& c, const ConsensusConfig& config);

// The median over the mover group's samples of the image distance (px) between where the mover's
// and the background's motions put them, over the median flow of all samples (px): how far apart
// the two motions lie against how fast the image moves. Infinite where the image stands still, 0
// without a mover group.
double moverSeparationShare(const FlowMotionSplit& split, const FlowCorrespondences& c, const CameraIntrinsics& camera);

// The share of the samples (only those of `mover_group_of`'s mover group when given) whose pixel in
// A lies where `where_a` (CV_8U, the camera's size, > 0) is set; 0 when there are none.
double samplesShareWhere(const FlowCorrespondences& c, const CameraIntrinsics& camera, const cv::Mat& where_a,
                         const FlowMotionSplit* mover_group_of = nullptr);

// Whether the split's mover group (the samples its motion explains better) holds at least
// min_mover_share of the samples, lies start_min_separation apart (moverSeparationShare) and not
// more than start_max_black_share of it on black pixels of `intensity_a` (A's grey levels, CV_32F,
// the camera's size; empty: not tested; not tested in a dim image either, kMostlyBlackFrame): at
// the start, before any scores, the best guess of the movers, even where their motion is too close
// to the background's for samples of their own, but not within the flow's own error nor on a black
// screen.
bool showsMoverGroup(const FlowMotionSplit& split, const FlowCorrespondences& c, const CameraIntrinsics& camera,
                     const ConsensusConfig& config, const cv::Mat& intensity_a = {});

// Whether the odometry's motion T_b_a_odometry is to restart from the split's background motion:
// it explains the mover's own flow (min_captured of the mover's own samples not on the static map,
// as `relation` says: it followed the mover, wholly or part way), or the background's motion
// explains at least min_gain of the samples more within 2 inlier_px.
bool misledOdometry(const FlowCorrespondences& c, const CameraIntrinsics& camera, const FlowMotionSplit& split,
                    const SE3& T_b_a_odometry, const ConsensusConfig& config,
                    const std::vector<MapRelation>& relation = {});

}  // namespace ff

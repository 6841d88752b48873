#pragma once
// The evidence behind the dynamic scores, one unit per kind: what it measures per cluster, the
// ScoreConfig settings it reads (its weight) and its test (tests/segmentation/test_score_evidence.cpp).
// computeDynamicScores (dynamic_score.h) assembles Eqs. 10-15 from them; a new cue is a new unit
// here and one line there (docs/design.md, "Where to add"). Why each default has its value:
// docs/tuning.md#scores.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <utility>
#include <vector>

#include "flowfusion/segmentation/clustering.h"
#include "flowfusion/segmentation/score_config.h"

namespace ff {

// A score above this is dynamic: the mask's threshold, and a carried score that was dynamic.
constexpr double kDynamicScore = 0.5;
// A cluster agrees with the map, or is remembered as moving, over more than this share of its pixels.
constexpr double kMostPixels = 0.5;
// A dynamic group covering more than this share of the clustered pixels is the background under
// a wrong pose, not a mover.
constexpr double kBackgroundShare = 0.5;

// Per cluster: the sum and count of |value| over the pixels of one residual image where it is
// finite. An empty image counts nothing (its term is left out). Throws InputError naming the image
// when it is not CV_32FC1 of the labels' size, or when a label is out of range.
struct ClusterMeans {
  std::vector<double> sum;
  std::vector<int> count;
  bool has(int c) const { return count[c] > 0; }
  double mean(int c) const;  // NaN without a valid pixel
};
ClusterMeans clusterMeans(const ClusterGraph& graph, const cv::Mat& image, const char* name);

// Eq. 10's motion terms (the paper): alpha_I mean(r_I) + mean(r_D) / D_i + alpha_F mean(r_F), each
// mean over its own valid pixels so that a missing term does not drop the others; `flow` is the
// alpha_F term alone, the motion cue that does not compare with the map (ScoreConfig::model_motion_cue).
struct MotionTerms {
  std::vector<double> delta;
  std::vector<double> flow;  // 0 where no r_F
};
MotionTerms motionTerms(const ClusterGraph& graph, const ClusterMeans& r_I, const ClusterMeans& r_D,
                        const ClusterMeans& r_F, const ScoreConfig& config);

// Model occlusion (our extension, weight alpha_M): alpha_M mean(r_M) / D_i, how far the cluster
// lies in front of the static map; 0 where no r_M. It flags a whole object in front of the mapped
// background, not only its moving edges. Per pixel, r_M is modelOcclusion's.
std::vector<double> modelOcclusionTerm(const ClusterGraph& graph, const ClusterMeans& r_M, const ScoreConfig& config);
// r_M per pixel: max(0, model_depth - depth - margin * depth), metres, CV_32F; NaN where either
// depth is missing. Both CV_32FC1 of one size (throws InputError otherwise).
cv::Mat modelOcclusion(const cv::Mat& depth, const cv::Mat& model_depth, double margin);

// Static agreement (our extension, weight model_agreement): the factor max(0, 1 - model_agreement
// mean(a_M)) on a cluster's motion terms, a the share of its pixels agreeing with the stable map;
// 1 where no a_M. Per pixel, a_M is modelAgreement's.
std::vector<double> staticAgreementFactor(const ClusterMeans& a_M, const ScoreConfig& config);
// 1 where |model_depth - depth| <= margin * depth, 0 where not, NaN where either depth is
// missing (CV_32F). With intensities (CV_32FC1 in [0, 1], the depth's size), also 0 where
// |model_intensity - intensity| > intensity_margin. All CV_32FC1 of one size (throws InputError
// otherwise).
cv::Mat modelAgreement(const cv::Mat& depth, const cv::Mat& model_depth, double margin, const cv::Mat& intensity = {},
                       const cv::Mat& model_intensity = {}, double intensity_margin = 1.0);

// Target mover share (our extension, target_mover_share): 1 for a cluster with at least that share
// of its pixels landing on the target's own movers and not agreeing with the map over most of its
// pixels. It was compared with nothing there, so a small residual is no evidence that it stands
// still.
std::vector<char> comparedWithNothing(const ClusterGraph& graph, const ClusterMeans& on_target_mover,
                                      const ClusterMeans& a_M, const ScoreConfig& config);

// Body smoothing (our extension, body_smoothing and body_depth_ratio): lambda_G's factor per edge
// of the graph, body_smoothing where the two clusters' mean depths differ by at most
// body_depth_ratio of the nearer (parts of one body), 1 elsewhere; empty when body_smoothing is 1.
std::vector<double> bodyEdgeScales(const ClusterGraph& graph, const ScoreConfig& config);

// Which groups of dynamic clusters move: the groups are the graph's connected clusters scoring
// above kDynamicScore, joined across edges within group_depth_ratio of depth. A group moves when
// one of its clusters' delta exceeds model_motion_delta (with model_motion_cue = flow against a
// map-built target: its flow term does, or the delta does in a remembered group). Motion memory
// (our extension, model_memory_s): a group is remembered when one of its clusters was moving
// recently over most of its pixels (MotionMemory::recall), unless it is the background
// (kBackgroundShare). Indexed by cluster; the group's decision at its root.
struct GroupMotion {
  std::vector<int> root;          // each cluster's group root (a cluster not dynamic is its own)
  std::vector<char> moves;        // at the root
  std::vector<char> remembered;   // at the root
  std::vector<char> minority;     // at the root: not the background
};
GroupMotion groupMotion(const ClusterGraph& graph, const Eigen::VectorXd& b, const std::vector<double>& delta,
                        const std::vector<double>& flow, const ClusterMeans& memory, bool r_D_from_map,
                        const ScoreConfig& config);

}  // namespace ff

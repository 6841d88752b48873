// Real sensor effects on the masks (issue 29): on static real TUM frames every marked pixel is
// wrong. The start of fr1/rpy turns 2-4 degrees a frame with real motion blur; there the optical
// flow fails over most of the view (median flow residual 5-8 px with the true motion), which
// marked 40-61 % of frames 1-5 dynamic until r_F was taken relative to the frame's own error
// (ScoreConfig::flow_error_px). Later, desks and shelves come into view 2-4 m away: a surface the
// map does not hold yet has a depth residual against its map-built keyframe and lies in front of
// the map's background, each depth cue confirming the other frame after frame until the flow
// alone could start a group's motion (ScoreConfig::model_motion_cue). The depth is taken up to
// 20 ms apart from the colour: the thin desk edges and chair legs 2 m away land a few pixels off
// their depth edge, over the far background, a metre of depth residual that kept them dynamic for
// 40 frames until r_D looked for the nearest matching depth (ScoreConfig::depth_window_px). What
// was left were marks of one or two clusters inside the view in 63 of the 150 frames, a few hundred
// to 7,000 pixels each, which the written mask now drops (PipelineOptions::mask_min_region).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/image_pyramid.h"
#include "flowfusion/eval/segmentation_metrics.h"
#include "flowfusion/eval/trajectory_metrics.h"
#include "flowfusion/flow/flow_residual.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/pipeline/flowfusion_system.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/test_util.h"

namespace ff {
namespace {

// The share of each frame's pixels marked dynamic, frames first..last (the run starting at first).
std::vector<double> markedShares(const TumSequence& seq, const SystemConfig& config, int last, int first = 0) {
  FlowFusionSystem system(config, seq.camera());
  std::vector<double> shares;
  for (int i = first; i <= last; ++i) {
    const FrameResult r = system.process(seq.load(i));
    shares.push_back(static_cast<double>(cv::countNonZero(r.dynamic_mask)) / r.dynamic_mask.total());
  }
  return shares;
}

// The optical flow as it was when the causes below were found: DIS fast, no consistency check, no
// error field. The finer flow with its check and field (ScoreConfig::flow_consistency_px,
// flow_error_field) hides most of each cause by itself, so each is shown with the flow of then.
void flowAsFound(SystemConfig& c) {
  c.flow.dis_preset = DisPreset::Fast;
  c.scores.flow_consistency_px = 0;
  c.scores.flow_error_field = FlowErrorField::kNone;
}

TEST(RealFrames, FastRotationStartOfStaticFr1RpyIsNotMarkedDynamic) {
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  SystemConfig config;
  const std::vector<double> now = markedShares(seq, config, 6);
  double mean = 0;
  for (int i = 1; i <= 6; ++i) mean += now[i] / 6;
  EXPECT_LT(mean, 0.08) << "frames 1-6 of static fr1/rpy: mean share marked dynamic";
  EXPECT_LT(now[1], 0.35);
  // The cause, shown: without the scaling the first scored frame is mostly marked.
  flowAsFound(config);
  config.scores.flow_error_px = 0;
  EXPECT_GT(markedShares(seq, config, 1)[1], 0.4);
}

// fr1/rpy turns 2-4 degrees a frame at its start and again from frame 120 (flow of 23-39 px): the
// first pair's split finds a second motion 2-4 px from the camera's (colour-depth offset, blur),
// which as the start's mover group marked a quarter of frame 1. A true mover at the start moved
// its samples 22-38 % of the image motion away in the scenes measured, these 8-9 %
// (ConsensusConfig::start_min_separation).
TEST(RealFrames, ASecondMotionWithinTheFlowsErrorAtAFastStartIsNoMover) {
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  for (const int first : {0, 120}) {
    SystemConfig config;
    const std::vector<double> now = markedShares(seq, config, first + 8, first);
    // Started at frame 0, frame 1 keeps 5.1 %: a blurred white patch at the left border that stands
    // out once the residual's affine field is taken out (scores.flow_error_field; 0 % without it,
    // 3.1 % with the paper's alpha_F).
    EXPECT_LT(*std::max_element(now.begin(), now.end()), 0.06) << "static fr1/rpy started at frame " << first;
    flowAsFound(config);
    config.consensus.start_min_separation = 0;
    EXPECT_GT(markedShares(seq, config, first + 1, first)[1], 0.15) << "the cause, started at frame " << first;
  }
}

// fr1/xyz moves slowly past two black monitors. Started at frame 20 or 200, the first pair's split
// found a second motion on them (89 % and 68 % of its samples black): a black screen's flow
// follows its reflections and what DIS fills in from around it. As the start's mover group it
// marked 8 % and 26 % of the first frames, and the carried scores held it for two more. Of the 42
// starts every 10 frames of both static heads, 11 groups lay 68-100 % on black pixels; the
// movers' groups of the augmented and synthetic scenes 0-47 % (ConsensusConfig::start_max_black_share).
TEST(RealFrames, ASecondMotionOnBlackScreensAtASlowStartIsNoMover) {
  const auto dir = testing::sharedTum("fr1_xyz_head300");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  for (const auto& [first, cause] : {std::pair{20, 0.06}, std::pair{200, 0.2}}) {
    SystemConfig config;
    const std::vector<double> now = markedShares(seq, config, first + 5, first);
    EXPECT_LT(*std::max_element(now.begin(), now.end()), 0.03) << "static fr1/xyz started at frame " << first;
    config.consensus.start_max_black_share = 1;
    const std::vector<double> before = markedShares(seq, config, first + 5, first);
    EXPECT_GT(*std::max_element(before.begin(), before.end()), cause) << "the cause, started at frame " << first;
  }
}

double meanOf(const std::vector<double>& v, int first, int last) {
  double sum = 0;
  for (int i = first; i <= last; ++i) sum += v[i];
  return sum / (last - first + 1);
}

// Frames first..last of static fr1/rpy: on average at most `fixed` of the pixels marked with the
// defaults, and more than `cause` with `undo` applied to them (the cause the default fixes) and
// small marks inside the view and the pixels the map holds written (the written mask's rules hide
// part of each cause).
void expectFixedOnFr1Rpy(int first, int last, double fixed, double cause, void (*undo)(SystemConfig&),
                         const char* why) {
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  SystemConfig config;
  EXPECT_LT(meanOf(markedShares(seq, config, last), first, last), fixed)
      << "frames " << first << "-" << last << " of static fr1/rpy";
  flowAsFound(config);
  undo(config);
  config.pipeline.mask_min_region = 0;
  config.pipeline.mask_map_agreement = false;
  EXPECT_GT(meanOf(markedShares(seq, config, last), first, last), cause) << "the cause: " << why;
}

TEST(RealFrames, SurfacesComingIntoViewOfStaticFr1RpyAreNotKeptDynamicByTheDepthAlone) {
  // Frames 82-107 (2.7-3.5 s): 3.4 % marked on average with any term starting the motion, 0.2 % now.
  // (Shown with the 6-DoF odometry: with the depth offset estimated (odometry.depth_offset_sigma_per_rad)
  // any term starting it marks 0.5 %: much of what the depth saw here was the sensor's drift.)
  expectFixedOnFr1Rpy(
      82, 107, 0.01, 0.02,
      [](SystemConfig& c) {
        c.scores.model_motion_cue = ModelMotionCue::kAnyTerm;
        c.odometry.depth_offset_sigma_per_rad = 0;
      },
      "the depth cues confirm each other");
}

TEST(RealFrames, ThinStructuresOfStaticFr1RpyAreNotMovedByADepthOutOfStepWithTheColour) {
  // Frames 27-69 (0.9-2.3 s): 0.3 % marked on average with the depth window, 4.4 % without it.
  expectFixedOnFr1Rpy(
      27, 69, 0.01, 0.03, [](SystemConfig& c) { c.scores.depth_window_px = 0; }, "desk edges a few pixels off");
}

TEST(RealFrames, ABlurredDeskTheFlowCannotFollowBackIsNoMotion) {
  // Frames 30-64 (1.0-2.1 s) with the finer flow (DIS medium) and small marks written: 3.7 % marked
  // on average without the forward-backward check (a desk 2.1-2.6 m away, blurred; a few clusters'
  // r_F of 5-10 px start it and the map then holds it out), 0.6 % with it.
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  SystemConfig config;
  config.pipeline.mask_min_region = 0;
  EXPECT_LT(meanOf(markedShares(seq, config, 64), 30, 64), 0.01) << "frames 30-64 of static fr1/rpy";
  config.scores.flow_consistency_px = 0;
  EXPECT_GT(meanOf(markedShares(seq, config, 64), 30, 64), 0.025) << "the cause: the flow's unchecked matches";
}

// Frame `cur`'s flow residual (segmentation level, px) against frame cur - 1 under the odometry's
// motion between the two (DenseOdometry with the defaults), with the affine field or the pose
// error's field taken out, and the depth it was taken at.
struct PairResiduals {
  cv::Mat depth, affine, parallax;
};
PairResiduals pairResiduals(const TumSequence& seq, int cur) {
  const RgbdFrame a = seq.load(cur), b = seq.load(cur - 1);
  const OdometryConfig oc;
  const SE3 T_b_a = DenseOdometry(oc)
                        .estimate(prepareOdometryFrame(a.intensity, a.depth, seq.camera(), oc),
                                  prepareOdometryFrame(b.intensity, b.depth, seq.camera(), oc))
                        .T_target_source;
  const cv::Mat depth = downsampleDepth(a.depth);
  const CameraIntrinsics cam = seq.camera().atLevel(1);
  const FlowField flow = resizeFlow(makeOpticalFlow(FlowConfig{})->compute(a.intensity, b.intensity), depth.size());
  const cv::Mat ego = egoFlow(depth, cam, T_b_a);
  return {depth, flowResidualWithoutAffine(flow, ego, 1.0), flowResidualWithoutPoseError(flow, ego, depth, cam, 1.0)};
}

// The median residual of the pixels nearer than near_m and of those farther.
struct NearFarResidual {
  double near_px, far_px;
};
NearFarResidual nearFarResidual(const cv::Mat& r, const cv::Mat& depth, double near_m) {
  cv::Mat near = r.clone(), far = r.clone();
  near.setTo(std::numeric_limits<float>::quiet_NaN(), depth >= near_m);
  far.setTo(std::numeric_limits<float>::quiet_NaN(), depth < near_m);
  return {finiteMedian(near), finiteMedian(far)};
}

TEST(RealFrames, NearSurfacesOfStaticFr1RpyAreNotMovedByTheOdometrysErrorOnBlurredFrames) {
  // Frames 50-54 (1.7 s) are the most blurred of the turn, and the odometry's translation there is
  // 1-2 cm off with or without segmentation. A white surface 0.85-0.99 m away enters at the lower
  // right (the rest of the view is 2-3 m away): with the affine field taken out, its median flow
  // residual under the frame-to-frame odometry's motion is 1.2 px (0.7 px under the true motion,
  // which has blur and errors of its own); in `run`, where the error was larger, it reached 4-9 px on
  // clusters with depth residuals below 2 mm and marked 2.9 % of frame 51. The parallax of the
  // translation error (scores.flow_error_field) takes it out: 0.45 px, the far surfaces' as before.
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  NearFarResidual affine{0, 0}, parallax{0, 0};
  constexpr int kFirst = 50, kLast = 54, kFrames = kLast - kFirst + 1;
  for (int cur = kFirst; cur <= kLast; ++cur) {
    const PairResiduals r = pairResiduals(seq, cur);
    const NearFarResidual a = nearFarResidual(r.affine, r.depth, 1.1), p = nearFarResidual(r.parallax, r.depth, 1.1);
    affine = {affine.near_px + a.near_px / kFrames, affine.far_px + a.far_px / kFrames};
    parallax = {parallax.near_px + p.near_px / kFrames, parallax.far_px + p.far_px / kFrames};
  }
  EXPECT_LT(parallax.near_px, 0.6) << "surfaces nearer than 1.1 m, frames 50-54: mean of the medians";
  EXPECT_LT(parallax.far_px, affine.far_px + 0.02) << "surfaces beyond 1.1 m";
  EXPECT_GT(affine.near_px, 1.0) << "the cause: the affine field alone";
}

TEST(RealFrames, SmallMarksInsideTheViewOfStaticFr1RpyAreNotWritten) {
  // Frames 20-69 (0.7-2.3 s): 25 of the 50 frames marked something without the rule, 1 with it.
  const auto dir = testing::sharedTum("fr1_rpy_head150");
  if (!dir) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence seq = TumSequence::open(*dir);
  auto framesMarked = [&](const SystemConfig& config) {
    const std::vector<double> shares = markedShares(seq, config, 69);
    return std::count_if(shares.begin() + 20, shares.end(), [](double s) { return s > 0; });
  };
  SystemConfig config;
  EXPECT_LE(framesMarked(config), 4) << "frames 20-69 of static fr1/rpy with any pixel marked";
  config.pipeline.mask_min_region = 0;
  EXPECT_GE(framesMarked(config), 15) << "the cause: single clusters with a residual of their own";
}

// `people` walkers and `objects` boxes composited by augment (seed) into the shared real sequence
// `head` (its frames up to last_frame, -1: all), written to `out`; nullopt when ../shared is absent.
// The cause tests made before generator version 3 keep their scenes with version 2's hole test
// (synth::HoleTest::Enclosed: a person shows through a black screen too large to be enclosed),
// where their causes show. All of them but the band's own test keep version 3's band
// (synth::BandDepth::Drawn: the movers' depth in the sensor's band), on which they were measured.
std::optional<TumSequence> withMovers(const std::string& head, synth::AugmentConfig config, const testing::TempDir& out) {
  const auto dir = testing::sharedTum(head);
  if (!dir) return std::nullopt;
  synth::augmentSequence(*dir, out.str(), config);
  return TumSequence::open(out.str());
}
std::optional<TumSequence> withMovers(const std::string& head, unsigned seed, int people, const testing::TempDir& out,
                                      int objects = 0, int last_frame = -1,
                                      synth::HoleTest holes = synth::HoleTest::BlackSurfaces) {
  synth::AugmentConfig config;
  config.holes = holes;
  config.band_depth = synth::BandDepth::Drawn;
  config.seed = seed;
  config.objects = objects;
  config.people = people;
  config.last_frame = last_frame;
  return withMovers(head, config, out);
}
// fr1/xyz with a box brought 0.6-1.0 m in front of the camera (augment seed 2902, xyz_near of
// docs/scenes.md), frames 0..last.
std::optional<TumSequence> withNearBox(int last, const testing::TempDir& out) {
  synth::AugmentConfig near;
  near.band_depth = synth::BandDepth::Drawn;
  near.seed = 2902;
  near.objects = 1;
  near.min_distance = 0.6;
  near.max_distance = 1.0;
  near.last_frame = last;
  return withMovers("fr1_xyz_head300", near, out);
}

// Frames 0..last against the sequence's true masks (masks/<timestamp>.png): each one's IoU, share
// of the pixels marked where the truth has none, and pose.
struct RunAgainstTruth {
  std::vector<double> iou;
  std::vector<double> falsely_marked;
  Trajectory trajectory;  // each frame's timestamp and T_world_cam
};
RunAgainstTruth runAgainstTruth(const TumSequence& seq, const SystemConfig& config, int last) {
  FlowFusionSystem system(config, seq.camera());
  RunAgainstTruth run;
  for (int i = 0; i <= last; ++i) {
    const RgbdFrame frame = seq.load(i);
    const FrameResult r = system.process(frame);
    const std::filesystem::path path = std::filesystem::path(*seq.masksDir()) / (timestampName(frame.timestamp) + ".png");
    const cv::Mat truth = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    const eval::MaskScores scores = eval::compareMasks(truth, r.dynamic_mask);
    run.iou.push_back(scores.iou);
    run.falsely_marked.push_back(static_cast<double>(scores.false_positive) / r.dynamic_mask.total());
    run.trajectory.push_back({frame.timestamp, r.T_world_cam});
  }
  return run;
}

// The written mask's rules leave the tracking alone: both runs have the same pose in every frame.
void expectSamePoses(const RunAgainstTruth& a, const RunAgainstTruth& b) {
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (size_t i = 0; i < a.trajectory.size(); ++i)
    EXPECT_TRUE(a.trajectory[i].T_world_cam.isApprox(b.trajectory[i].T_world_cam, 1e-12)) << "frame " << i;
}

// fr1/rpy with `people` walkers composited by augment (seed, version 2's hole test: both causes
// below began with the person drawn through the black monitor): frames first..last on average at most
// 0.5 % falsely marked (against the true masks) with the defaults and more than 1.5 % with `undo` (the
// cause the default fixes). Both causes below were first marked by the fast start's mover group,
// which consensus.start_min_separation no longer takes: they are shown with it back.
void expectFixedWithPeople(unsigned seed, int people, int first, int last, void (*undo)(SystemConfig&),
                           const char* why) {
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", seed, people, tmp, 0, -1, synth::HoleTest::Enclosed);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence& seq = *augmented;
  SystemConfig config;
  const double fixed = meanOf(runAgainstTruth(seq, config, last).falsely_marked, first, last);
  flowAsFound(config);
  undo(config);
  config.consensus.start_min_separation = 0;
  const double cause = meanOf(runAgainstTruth(seq, config, last).falsely_marked, first, last);
  std::printf("[ measured ] frames %d-%d falsely marked %.2f %%, with the cause %.2f %%\n", first, last, 100 * fixed,
              100 * cause);
  EXPECT_LT(fixed, 0.005) << "frames " << first << "-" << last << " of augment seed " << seed;
  EXPECT_GT(cause, 0.015) << "the cause: " << why;
}

TEST(RealFrames, AScreensSpecklesDoNotTakeTheMotionOfASurfaceBehindThem) {
  // fr1/rpy with a person walking behind the desk's black monitor (augment, the issue-29 scene
  // rpy_people): after the person has gone, the screen's speckles (0.88 m) were one dynamic group
  // with a surface 0.29 m behind them and kept the map's occlusion term, frames 142-149 marked
  // 7,500-15,900 pixels each; with groups within scores.group_depth_ratio, frames 143-149 none.
  expectFixedWithPeople(
      2901, 1, 143, 149, [](SystemConfig& c) { c.scores.group_depth_ratio = 0; }, "groups at any depth");
}

TEST(RealFrames, ASurfaceEarlierFramesSawStandingThereIsNotTakenForTheMoverBesideIt) {
  // fr1/rpy with a person walking at the top left corner (augment seed 92, the held-out scene
  // n_rpy_people of docs/scenes.md): in frames 118-130 the black monitor in front of surfels fused
  // from other viewpoints was marked in the person's place, 9,000-17,000 pixels a frame, held by
  // the map's occlusion term; earlier frames saw the monitor standing there, so with
  // scores.model_views that term is withheld and nothing is marked there.
  expectFixedWithPeople(
      92, 1, 118, 130, [](SystemConfig& c) { c.scores.model_views = 0; }, "the map's occlusion alone");
}

// The mean IoU of frames first..last.
double meanIoU(const TumSequence& seq, const SystemConfig& config, int first, int last) {
  return meanOf(runAgainstTruth(seq, config, last).iou, first, last);
}

TEST(RealFrames, APersonWalkingWithTheCamerasPanIsFoundOverALongerBaseline) {
  // fr1/xyz with two people walking (augment seed 91, the held-out scene n_xyz_people2 of
  // docs/scenes.md): in frames 106-121 a person walks with the slow camera, 1-3 px a frame
  // against the room, within the frame's own flow error; against the frame four back the motion
  // adds up (scores.long_baseline_frames), and the person is found: mean IoU 0.80 against 0.34
  // (0.58 against 0.14 with the paper's alpha_F and DIS fast; 0.93 before the chain's noise was
  // scaled, scores.long_baseline_noise_px: frames 107-110 find less of the person, 0.25-0.61).
  // Without the hold of scores.hold_seen_moving_s, which keeps part of the person the long
  // baseline once found (0.49 with one frame pair alone). Version 2's hole test: at version 3 the
  // black monitor hides part of the person, and the long baseline and one frame pair find what
  // shows alike (0.51 and 0.50). Without pipeline.mask_band_reach_px: here the person has depth
  // in the sensor's band, so the band's pixels without depth beside it are the room's, and those
  // of the person's colours are written (0.67 with it); at version 4 the person is in the band in
  // these frames (0.13 with the default settings, with it or without).
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_xyz_head300", 91, 2, tmp, 0, -1, synth::HoleTest::Enclosed);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const TumSequence& seq = *augmented;
  SystemConfig config;
  config.scores.hold_seen_moving_s = 0;
  config.pipeline.mask_band_reach_px = 0;
  EXPECT_GT(meanIoU(seq, config, 106, 121), 0.7) << "frames 106-121 with the long baseline";
  config.scores.long_baseline_frames = 0;
  EXPECT_LT(meanIoU(seq, config, 106, 121), 0.45) << "the cause: one frame pair alone";
}

TEST(RealFrames, TheBackgroundBesideAPersonThatTheMapHoldsIsNotWritten) {
  // fr1/rpy with a person walking at the right (augment seed 2901, the issue-29 scene rpy_people
  // of docs/scenes.md): in frames 83-99 the wall and the monitor's frame above the person, mapped
  // long before, were written dynamic with the person's clusters (held by their neighbours, the
  // carried score and the motion memory). Their pixels coincide with the stable map in depth and
  // grey level, and the written mask leaves them out (pipeline.mask_map_agreement): mean IoU 0.85
  // against 0.68, 4,100 falsely marked pixels a frame against 14,800. Only the written mask: the
  // poses are the same. (Without the hold of scores.hold_seen_moving_s, which moves the poses and
  // brings these frames to 0.80 with the rule: rpy_people 0.824 -> 0.814, docs/tuning.md.)
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 2901, 1, tmp);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  SystemConfig config;
  config.scores.hold_seen_moving_s = 0;
  const RunAgainstTruth with = runAgainstTruth(*augmented, config, 99);
  config.pipeline.mask_map_agreement = false;
  const RunAgainstTruth without = runAgainstTruth(*augmented, config, 99);
  EXPECT_GT(meanOf(with.iou, 83, 99), 0.8) << "frames 83-99 without the pixels the map holds";
  EXPECT_LT(meanOf(without.iou, 83, 99), 0.75) << "the cause: the background written with the person";
  expectSamePoses(with, without);
}

TEST(RealFrames, APersonFoundBeforeARestartFromTheFlowIsNotLost) {
  // fr1/rpy with a person walking at the right (augment seed 2901, rpy_people of docs/scenes.md):
  // in frames 1-6 the fast rotation misleads the first odometry and the flow's consensus restarts
  // it in four of them. With nothing carried after a restart, frame 6 loses the person, and the
  // static scores carried from then on hold them lost: frames 7-11 mean IoU 0.09. Carried through
  // the restarts where they said dynamic (scores.restart_keeps_movers), the previous scores keep
  // the person: 0.97. (From frame 12 only a sliver of the person, without depth, shows at the top
  // edge, its image motion close to the camera's (flow residual 0.3 px): nothing says it moves, and
  // how long the carried score outlasts that follows small differences of the poses: to frame 15
  // with a 6-DoF odometry, to frame 11 with the depth offset.) Version 2's hole test: at version 3
  // the black monitor hides most of the person in frames 7-12.
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 2901, 1, tmp, 0, -1, synth::HoleTest::Enclosed);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  SystemConfig config;
  EXPECT_GT(meanIoU(*augmented, config, 7, 11), 0.8) << "frames 7-11 with the movers carried";
  config.scores.restart_keeps_movers = false;
  EXPECT_LT(meanIoU(*augmented, config, 7, 11), 0.3) << "the cause: nothing carried after a restart";
}

// Frames 0..last of `seq` with `config`, and again with `cause` applied to it (the rule under test
// turned off): both runs, the mean IoU over frames first..last of each and, where `seq` has a
// ground truth, the ATE of each over frames 0..last, printed.
struct CauseRuns {
  RunAgainstTruth with, without;
  double with_iou = 0, without_iou = 0;
  double with_ate_m = std::numeric_limits<double>::quiet_NaN(), without_ate_m = with_ate_m;
};
CauseRuns runWithAndWithoutCause(const TumSequence& seq, SystemConfig config,
                                 const std::function<void(SystemConfig&)>& cause, int first, int last) {
  CauseRuns r;
  r.with = runAgainstTruth(seq, config, last);
  cause(config);
  r.without = runAgainstTruth(seq, config, last);
  r.with_iou = meanOf(r.with.iou, first, last);
  r.without_iou = meanOf(r.without.iou, first, last);
  std::printf("[ measured ] frames %d-%d mean IoU %.2f, with the cause %.2f\n", first, last, r.with_iou,
              r.without_iou);
  if (const auto& truth = seq.groundtruth()) {
    r.with_ate_m = eval::computeAte(*truth, r.with.trajectory).translation_m.rmse;
    r.without_ate_m = eval::computeAte(*truth, r.without.trajectory).translation_m.rmse;
    std::printf("[ measured ] frames 0-%d ATE %.1f mm, with the cause %.1f mm\n", last, 1e3 * r.with_ate_m,
                1e3 * r.without_ate_m);
  }
  return r;
}

TEST(RealFrames, ASmallBoxInsideTheViewSeenMovingIsWritten) {
  // fr1/rpy with a box and a person (augment seed 94, the held-out scene n_rpy_mixed of
  // docs/scenes.md): in frames 133-141 the box, 2,100-6,500 pixels inside the view, is scored
  // dynamic and seen moving with a flow of its own, but under 2 % of the image the written mask
  // dropped it whole (mean IoU 0). Held by clusters seen moving with a flow residual of at least
  // pipeline.mask_keep_flow_px, off the static map, it is written: 0.86. (Without the hold of
  // scores.hold_seen_moving_s, which takes the same clusters and moves the poses.)
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 94, 1, tmp, 1);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  SystemConfig config;
  config.scores.hold_seen_moving_s = 0;
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, config, [](SystemConfig& c) { c.pipeline.mask_keep_flow_px = 0; }, 133, 141);
  EXPECT_GT(r.with_iou, 0.6) << "frames 133-141, the box kept";
  EXPECT_LT(r.without_iou, 0.1) << "the cause: a small mark inside the view, dropped";
  expectSamePoses(r.with, r.without);
}

TEST(RealFrames, ABoxThatStopsIsHeldWhereTheScoresSawItMove) {
  // The same scene: the box, 1.0-1.1 m away between the monitors, was seen moving with a flow of
  // its own (r_F 10-16 px in frame 76); over frames 80-90 it moves slowly (r_F 3-4 px), the carried
  // prior gives way and the mask loses it (mean IoU 0.28). Held where the scores last saw it move
  // clearly, off the stable map (scores.hold_seen_moving_s): 0.75.
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 94, 1, tmp, 1);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.scores.hold_seen_moving_s = 0; }, 80, 90);
  EXPECT_GT(r.with_iou, 0.6) << "frames 80-90, the box held";
  EXPECT_LT(r.without_iou, 0.4) << "the cause: nothing holds a mover once its motion is weak";
}

TEST(RealFrames, ABoxNearerThanTheSensorsRangeIsWrittenWhereItsFlowMoves) {
  // fr1/xyz with a box brought 0.6-1.0 m in front of the camera (xyz_near): in frames 104-133 its
  // front face, nearer than the sensor's range, has no depth; its hole runs into the sensor's band,
  // borders the desk as much as the box's sides and is not filled (mask_hole_share): mean IoU 0.31.
  // Where its optical flow, which no static depth around it explains, lies beside the box's marked
  // sides, it is written (pipeline.mask_hole_flow_px): 0.79 with the sensor's band (the run's
  // median width, SensorBandMedian) tested by the band's own rule (pipeline.mask_band_holes), 0.76
  // with the band left out, 0.66 when the band left out was each frame's own, which the face widens
  // to a tenth of the width at the left border. Only the written mask: the poses are the same.
  const testing::TempDir tmp;
  const auto augmented = withNearBox(133, tmp);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.pipeline.mask_hole_flow_px = 0; }, 104, 133);
  EXPECT_GT(r.with_iou, 0.7) << "frames 104-133, the box's face written";
  EXPECT_LT(r.without_iou, 0.4) << "the cause: a hole without depth the fill leaves open";
  expectSamePoses(r.with, r.without);
}

TEST(RealFrames, APersonsPartInTheSensorsBandIsWrittenWhereItsFlowMovesBesideTheRest) {
  // fr1/xyz with two walkers (augment seed 91, n_xyz_people2 of docs/scenes.md) pasted as a Kinect
  // returns them: no depth in the sensor's band (band_depth none; on fr1 about 45 rows at the top).
  // In frames 1-8 the people's heads and shoulders lie in the top band: no depth, no cluster, so
  // their part there is written only where its flow, which no static depth explains, moves beside
  // the written rest of them and its colour is the people's rather than the room's
  // (pipeline.mask_band_holes): mean IoU 0.73 against 0.53 without (0.79 before the colour was
  // asked). Only the written mask: the poses are the same.
  const testing::TempDir tmp;
  synth::AugmentConfig config;
  config.seed = 91;
  config.objects = 0;
  config.people = 2;
  config.last_frame = 8;
  config.band_depth = synth::BandDepth::None;
  const auto augmented = withMovers("fr1_xyz_head300", config, tmp);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.pipeline.mask_band_holes = false; }, 1, 8);
  EXPECT_GT(r.with_iou, 0.7) << "frames 1-8, the people's part in the band written";
  EXPECT_LT(r.without_iou, 0.6) << "the cause: the band never tested";
  expectSamePoses(r.with, r.without);
}

TEST(RealFrames, TheWrittenMasksEdgeFollowsTheMoversDepthEdge) {
  // The same box (xyz_near), frames 60-104, where it is found: the scores are per cluster at half
  // size, scaled up pixel for pixel, so the mask's edge lies a pixel or two off the box's and takes
  // in pixels without depth beside it: 2,300 falsely marked pixels a frame (0.74 % of the image).
  // Refined at the input's resolution (pipeline.mask_edge_px: each pixel near the edge joins the
  // side whose depth it is nearer, or without depth, whose colour): 1,850 (0.60 %), mean IoU 0.95 ->
  // 0.96. Only the written mask: the poses are the same.
  const testing::TempDir tmp;
  const auto augmented = withNearBox(104, tmp);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.pipeline.mask_edge_px = 0; }, 60, 104);
  const double with_false = meanOf(r.with.falsely_marked, 60, 104);
  const double without_false = meanOf(r.without.falsely_marked, 60, 104);
  std::printf("[ measured ] frames 60-104 falsely marked %.4f of the image, with the cause %.4f\n", with_false,
              without_false);
  EXPECT_LT(with_false, 0.9 * without_false) << "frames 60-104, the edge refined";
  EXPECT_GE(r.with_iou, r.without_iou);
  expectSamePoses(r.with, r.without);
}

TEST(RealFrames, ABoxOverHalfTheFirstViewIsTheMoverNotTheDesk) {
  // fr1/rpy with a box and a person (augment seed 2094, n_rpy_mixed of the seeds + 2000 set in
  // docs/scenes.md): from the first frame a box 0.6-1 m away and the person cover about half of the
  // view. The split's larger group was the box's, the map is the first frame (box and all), and the
  // start took the box for the world and the desk for the mover: frames 1-14 mean IoU 0.18 (0.06
  // since the previous frame's movers count as in front of the map, consensus.previous_movers_in_front,
  // which then holds the swapped roles). Of two groups of comparable size the nearer moves
  // (consensus.nearer_mover_depth_ratio): 0.42, the desk no longer marked from frame 5. Version 2's
  // hole test: at version 3 the start does not swap the roles here even without the rule.
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 2094, 1, tmp, 1, -1, synth::HoleTest::Enclosed);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.consensus.nearer_mover_depth_ratio = 0; }, 1, 14);
  EXPECT_GT(r.with_iou, 0.35) << "frames 1-14, the nearer group the mover";
  EXPECT_LT(r.without_iou, 0.25) << "the cause: the larger group, the box, taken for the world";
}

TEST(RealFrames, ABoxThePreviousScoresHeldIsNotTakenForTheWorld) {
  // fr1/xyz with two boxes (augment seed 2095, n_xyz_objects of the seeds + 2000 set in
  // docs/scenes.md): from the first frame a box 0.5 m away covers a quarter to half of the view,
  // found from frame 1. Frame 10 comes 64 ms after frame 9 and the box moves 30 px: the flow's
  // split takes the box's group (423 samples) for the world's and the desk's (228) for the mover's,
  // the groups too unequal for the nearer-is-the-mover rule, and the map has nothing behind the box
  // to say otherwise. The correct odometry looked captured, was restarted on the box's motion and
  // jumped 16 cm: frames 0-11 ATE 40 mm. The box's samples lay where frame 9's scores held a mover,
  // which counts as in front of the map (consensus.previous_movers_in_front): the roles stay, 6 mm.
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_xyz_head300", 2095, 0, tmp, 2, 11);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  ASSERT_TRUE(augmented->groundtruth());
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.consensus.previous_movers_in_front = false; }, 10, 11);
  EXPECT_LT(r.with_ate_m, 0.010) << "frames 0-11, the box held for the mover";
  EXPECT_GT(r.without_ate_m, 0.025) << "the cause: the odometry restarted on the box's motion";
  EXPECT_GT(r.with_iou, 0.9) << "frames 10-11";
  EXPECT_LT(r.without_iou, 0.8) << "the cause: the desk beside the box marked";
}

TEST(RealFrames, AUniformBoxOverHalfTheFirstViewIsNotTakenForTheWorld) {
  // fr1/rpy with a box and a person (augment seed 2094, n_rpy_mixed of the seeds + 2000 set in
  // docs/scenes.md): in the first frame a flat-coloured box 0.57 m away covers 40 % of the view
  // beside a blurred desk 1.06 m away. The start's split found the box's group the larger (428
  // samples against 207), too unequal for the nearer-is-the-mover rule, so the desk was marked
  // and the odometry followed the box. Counted over the samples where the image is textured (78
  // against 116; the box's flow is filled in from its outline), the desk's is the world's motion
  // (consensus.start_min_texture): frames 1-6 mean IoU 0.88 against 0.28, frames 0-6 ATE 6.8 mm
  // against 10.4 mm. Version 2's hole test: at version 3, with less of
  // the person in view, the start goes otherwise (frames 1-6: 0.43 with the rule).
  const testing::TempDir tmp;
  const auto augmented = withMovers("fr1_rpy_head150", 2094, 1, tmp, 1, 6, synth::HoleTest::Enclosed);
  if (!augmented) GTEST_SKIP() << testing::sharedDataMissing();
  ASSERT_TRUE(augmented->groundtruth());
  const CauseRuns r = runWithAndWithoutCause(
      *augmented, SystemConfig{}, [](SystemConfig& c) { c.consensus.start_min_texture = 0; }, 1, 6);
  EXPECT_GT(r.with_iou, 0.7) << "frames 1-6, the box found";
  EXPECT_LT(r.without_iou, 0.4) << "the cause: the desk marked";
  EXPECT_LT(r.with_ate_m, 0.8 * r.without_ate_m) << "the odometry kept off the box";
}

}  // namespace
}  // namespace ff

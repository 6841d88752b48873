#pragma once
// The per-frame FlowFusion system (paper Fig. 1): robust odometry against a tracking target, the
// segmentation loop (flow, clusters, dynamic scores, weighted odometry), fusion of the static
// background into a surfel map. docs/design.md draws the pipeline and its frame conventions.
#include <chrono>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/timings.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/pipeline/segmentation_loop.h"
#include "flowfusion/pipeline/system_config.h"
#include "flowfusion/pipeline/tracking_target.h"
#include "flowfusion/segmentation/cluster_log.h"
#include "flowfusion/slam/loop_closer.h"
#include "flowfusion/slam/map_file.h"

namespace ff {

struct FrameResult {
  double timestamp = 0;
  SE3 T_world_cam = SE3::Identity();
  bool tracking_ok = true;
  // False before a run continuing in a saved map is localized in it: T_world_cam means nothing.
  bool has_pose = true;
  std::string message;          // what the tracker did when it did not simply succeed
  bool used_model = false;      // aligned to the map prediction (frame_to_model or a model keyframe)
  bool restarted_from_flow = false;  // the odometry was restarted from the flow's rigid consensus
  int iterations = 0;           // segmentation rounds
  cv::Mat dynamic_mask;         // CV_8U, input size, 255 = dynamic, in this frame's pixels
  cv::Mat scores;               // CV_32F b per pixel at the segmentation level (empty when off)
  ClusterLog clusters;          // each cluster's evidence and score (pipeline.cluster_log; else empty)
};

// A run continuing in a saved map (`run --map-in`): where it came from and when the run found
// itself in it.
struct MapReuse {
  std::string path;
  int keyframes = 0;           // loaded
  size_t surfels = 0;          // loaded
  int localized_at_frame = -1; // the first frame whose pose was found in it (-1: none yet)
  int unlocalized_frames = 0;  // frames before that: no pose, not fused, not in the trajectory
};

class FlowFusionSystem {
 public:
  // Throws InputError naming the first bad setting. With `map_in` (slam/map_file.h) the run
  // continues in a saved map: its surfels and keyframes are loaded, each frame is sought against
  // the keyframes (as a relocalization) until one is found, and from that frame on the run tracks
  // and fuses in the saved map's world frame (T_world_first is not used); the frames before have
  // no pose. An InputError naming the map file when it does not fit (checkMapFits) or loop
  // closure is off.
  FlowFusionSystem(const SystemConfig& config, const CameraIntrinsics& camera,
                   const SE3& T_world_first = SE3::Identity(), const SavedMap* map_in = nullptr);
  // Neither copied nor moved: the stages running beside others hold `this`.
  FlowFusionSystem(const FlowFusionSystem&) = delete;
  FlowFusionSystem& operator=(const FlowFusionSystem&) = delete;

  // Processes the next frame (in time order) and returns its pose and mask. Stage times are added
  // to timings() under "odometry", "flow", "consensus", "clustering", "scores", "prediction", "fusion".
  // Three stages run beside others on worker threads, the results the same as one after the other:
  // the flow and the clusters beside the first odometry, and the frame's fusion into the map beside
  // the next frame's tracking until that reads the map (its time lands in the row of the frame that
  // waited for it). The frame's images must stay unchanged until the next frame is processed.
  FrameResult process(const RgbdFrame& frame);

  // The poses as tracked (what each FrameResult said).
  const Trajectory& trajectory() const { return trajectory_; }
  // The poses after the last loop closure (slam/loop_closer.h); the tracked ones when loop closure
  // is off or closed no loop.
  Trajectory closedTrajectory() const { return slam_ ? slam_->trajectory() : trajectory_; }
  // At the end of a run: waits for the loop checks still running and applies what they found to
  // the map and closedTrajectory().
  void finishLoopClosure();
  bool loopClosureActive() const { return slam_ != nullptr; }
  int loopClosures() const { return slam_ ? slam_->loopClosures() : 0; }
  int loopCorrections() const { return slam_ ? slam_->corrections() : 0; }
  // With loop closure: frames whose tracking failed (not fused), and those of them whose pose was
  // found again against the keyframes (tracking restarts there).
  int lostFrames() const { return lost_frames_; }
  int relocalizedFrames() const { return relocalized_frames_; }
  int slamKeyframes() const { return slam_ ? slam_->keyframes() : 0; }
  // The loop closer's keyframes at their corrected poses (a saved map's first), for the run's map
  // file; empty without loop closure. Call after finishLoopClosure().
  std::vector<SavedKeyframe> savedKeyframes() const {
    return slam_ ? slam_->savedKeyframes() : std::vector<SavedKeyframe>{};
  }
  // Set when the run continues in a saved map.
  const std::optional<MapReuse>& mapReuse() const { return map_reuse_; }
  // Why loop closure is off although configured (a build without Ceres); empty otherwise.
  const std::string& loopClosureNote() const { return slam_note_; }
  // The map up to the last processed frame (waits for that frame's fusion).
  const StaticMap* map() const;
  // Waits likewise, so the last fusion's time is in.
  Timings& timings();
  const Timings& timings() const;
  // process()'s wall time per frame (ms): stages that run at the same time count once.
  const std::vector<double>& frameMs() const { return frame_ms_; }
  const SystemConfig& config() const { return config_; }
  const CameraIntrinsics& camera() const { return camera_; }
  int trackingFailures() const { return failures_; }
  int flowRestarts() const { return flow_restarts_; }

 private:
  OdometryFrame prepare(const RgbdFrame& frame);
  // The odometry against the chosen target from the guess T_prev_cur_guess, weighted by the
  // carried scores; a rendered target that fails gives way to the previous frame.
  MotionEstimate firstOdometry(const OdometryFrame& cur, TrackingTarget& target, SE3& T_target_prev,
                               const SE3& T_prev_cur_guess, const cv::Mat& carried, FrameResult& result);
  // What tracking leaves for the frame's mask, at the segmentation level (both empty without
  // segmentation): the scores b, and where the frame coincides with the stable map.
  struct TrackedScores {
    cv::Mat scores;
    cv::Mat map_agreement;
    cv::Mat seen_moving;  // MotionEstimate::seen_moving
    cv::Mat moving_holes;  // MotionEstimate::moving_holes
    cv::Mat sensor_band;   // MotionEstimate::sensor_band
    ClusterLog clusters;
  };
  // Odometry and segmentation against the target.
  TrackedScores track(const RgbdFrame& frame, const OdometryFrame& cur, FrameResult& result);
  // The written mask after the tracking, the fusion and the next targets have used the scores:
  // without the pixels the stable map holds (pipeline.mask_map_agreement), the small marks inside
  // the view (mask_min_region) but those on clusters seen moving (mask_keep_flow_px), and with the
  // depth holes of a mover filled (mask_hole_share) or moving with it (mask_hole_flow_px), its edge
  // refined at the input's resolution (mask_edge_px).
  void finishWrittenMask(const RgbdFrame& frame, const TrackedScores& tracked, cv::Mat& mask) const;
  // Starts fusing the frame into the map on a worker thread (every fusion_every frames; a frame
  // past its budget leaves it to the next, up to 2 x fusion_every frames unfused).
  // Returns whether it started one.
  bool startFusion(const RgbdFrame& frame, const SE3& T_world_cam, const cv::Mat& full_scores, bool late);
  // Applies the loop closures due: the map's surfels and the tracker's poses move to the corrected
  // world frame (waiting for a check timed as "loop_closure", moving the map as "loop_correction").
  void applyLoopCorrections();
  // After a failed tracking (with loop closure): the frame's pose from the keyframes; found, the
  // frame counts as tracked and the tracking targets start again from it (timed as "relocalization").
  void relocalize(const RgbdFrame& frame, FrameResult& result, cv::Mat& scores);
  // The constructor's part for a saved map.
  void continueIn(const SavedMap& map);
  // Until the run is found in the saved map: seeks the frame against its keyframes; found, the
  // frame becomes the run's first, at that pose aligned to the map (refinedInSavedMap). Returns
  // whether the frame has a pose.
  bool localizeInSavedMap(const RgbdFrame& frame, const OdometryFrame& cur, FrameResult& result);
  // The pose found against one keyframe's small images, aligned to the whole map's rendering there
  // (colour and depth, as frame-to-model tracking; unchanged without a map or when that fails).
  SE3 refinedInSavedMap(const OdometryFrame& cur, const SE3& T_world_cam) const;
  // Waits for the fusion started last, if one is running, and adds its time to timings_.
  void finishFusion() const;
  // The pose reported at the colour image's time, moved from the depth image's along the last motion.
  SE3 atColourTime(const RgbdFrame& frame, const SE3& T_world_cam) const;

  SystemConfig config_;
  CameraIntrinsics camera_;
  DenseOdometry odometry_;
  std::unique_ptr<SegmentationLoop> segmentation_;
  std::unique_ptr<StaticMap> map_;
  TrackingTargets targets_;
  SE3 T_world_first_;
  SE3 T_prev_cur_velocity_ = SE3::Identity();  // last frame-to-frame motion, the next guess
  double velocity_dt_ = 0;                      // s, the time that motion took
  Trajectory trajectory_;
  // Mutable: the const accessors wait for the background fusion and record its time.
  mutable Timings timings_;
  std::vector<double> frame_ms_;
  // When the frame being processed runs out of pipeline.budget_ms (max(): no budget).
  std::chrono::steady_clock::time_point deadline_ = std::chrono::steady_clock::time_point::max();
  int frames_since_fusion_;  // processed frames since the last fusion, this one included
  int failures_ = 0;
  int flow_restarts_ = 0;
  std::unique_ptr<SlamBackEnd> slam_;  // null: loop closure off
  std::string slam_note_;
  int lost_frames_ = 0;
  int relocalized_frames_ = 0;
  std::optional<MapReuse> map_reuse_;
  // The fusion running on a worker (its duration in ms); last, so it ends before the map goes.
  mutable std::future<double> fusion_;
};

}  // namespace ff

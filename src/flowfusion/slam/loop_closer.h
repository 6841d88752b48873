#pragma once
// The back end that turns odometry into SLAM: keyframes as the camera moves, loops found among
// them (place index, geometric check) and the keyframe pose graph solved with Ceres, all on a
// background thread; the tracking thread hands over each frame and takes the corrections.
//
// Reproducible whatever the thread timing: a keyframe's check starts from what the tracking
// thread knew when the keyframe was made, and its result is applied slam.apply_after_frames frames
// later (the tracking thread waits there only if the check is still running). A correction moves
// every keyframe; a frame keeps its pose relative to the keyframe that was the latest when it was
// tracked and to the next one, and moves with both by how far along it lies between them (a jump
// tracked between two keyframes is spread over their frames, docs/tuning.md#robust-odometry-edges);
// the map's surfels move with the keyframe that was the latest when they were created (their map
// integration's anchor). Frames whose tracking failed are bridged once it is regained (by the view
// returning or by relocalize()): they take the poses interpolated on SE(3), by time, between the last
// frame tracked before them and the first after, and move with their keyframe as tracked frames do
// (the live FrameResult keeps what the tracker said; docs/tuning.md#relocalization).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/odometry/dense_odometry.h"
#include "flowfusion/slam/keyframe.h"
#include "flowfusion/slam/slam_config.h"

namespace ff {

// What the tracking thread hands over after each frame.
struct TrackedFrameInfo {
  const RgbdFrame* frame = nullptr;
  SE3 T_world_cam;           // the tracked pose (the depth image's time): keyframes take it
  SE3 T_world_cam_reported;  // the pose the trajectory reports (the colour image's time)
  bool tracking_ok = true;
  cv::Mat scores;            // b per pixel at any level, empty for all static
  bool fused = false;        // the frame was integrated into the map (its surfels anchor here)
};

// A loop closure's effect on what the tracking thread holds, T_new_old: old world -> corrected.
struct MapCorrection {
  SE3 T_new_old_current;                      // the tracker's frame (the latest keyframe's correction)
  std::vector<SE3> T_new_old_by_integration;  // the map's surfels, by the integration that created them
};

class SlamBackEnd {
 public:
  virtual ~SlamBackEnd() = default;
  virtual void frameTracked(const TrackedFrameInfo& info) = 0;
  // The next correction due before the next frame, if any (waits for its check when it still
  // runs); call until it returns none.
  virtual std::optional<MapCorrection> takeCorrection() = 0;
  // After a tracking failure: the pose of `frame` found against the keyframes (the place index's
  // best candidates, each checked as a loop is, from the candidate's own pose), none when no check
  // passes. `scores`: b per pixel, empty for all static. Waits for the checks still running (the
  // index is theirs) without applying them.
  virtual std::optional<SE3> relocalize(const RgbdFrame& frame, const cv::Mat& scores) = 0;
  // Makes every check still running due, so takeCorrection() returns the rest (the run's end), and
  // after them one last solve of the whole graph when loops were found whose solves moved too
  // little to be applied while tracking went on.
  virtual void finish() = 0;
  // The trajectory after the last applied correction: each frame's reported pose moved with the
  // keyframes before and after it (as tracked until a loop closes, lost frames bridged).
  virtual Trajectory trajectory() const = 0;
  // Before the first frame: the keyframes of a saved map (slam/map_file.h, `run --map-in`), indexed
  // for relocalize() and the loop checks and held fixed in the pose graph: they are the world frame
  // the run continues in. The run's own first keyframe joins the graph through the keyframe its
  // pose was found against.
  virtual void loadKeyframes(const std::vector<SavedKeyframe>& keyframes) = 0;
  // Every keyframe kept with its images (loaded ones first) at its pose after the last applied
  // correction, for the run's map file; waits for the checks still running.
  virtual std::vector<SavedKeyframe> savedKeyframes() const = 0;
  virtual int loopClosures() const = 0;  // verified loop edges in the graph
  virtual int corrections() const = 0;   // solved graphs applied (past slam.min_correction_m / _deg)
  // Keyframes kept with their images (loaded ones included; slam.cull_covered_keyframes drops the
  // images of those whose view an older keyframe covers); waits for the checks still running.
  virtual int keyframes() const = 0;
};

// The back end slam.loop_closure names; null for off, and for ferns in a build without Ceres
// (then `note`, when given, says so and how to enable it).
std::unique_ptr<SlamBackEnd> makeSlamBackEnd(const SlamConfig& config, const OdometryConfig& odometry,
                                             const CameraIntrinsics& camera, std::string* note = nullptr);

}  // namespace ff

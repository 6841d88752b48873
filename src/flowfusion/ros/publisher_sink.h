#pragma once
// The ResultSink that publishes a run on ROS: per frame ~odometry (nav_msgs/Odometry, the pose of
// the camera frame in the map frame, stamped with the colour image's stamp), the TF map -> camera,
// ~path (nav_msgs/Path of the run so far) and ~mask (mono8, 255 = dynamic, in the colour image's
// pixels and stamp); ~static_cloud (sensor_msgs/PointCloud2 of the map's stable surfels: x, y, z,
// rgb) at most once per ~map_period_s, from the run's thread between frames. Messages are built
// only for topics someone subscribes to.
#include <chrono>
#include <mutex>
#include <nav_msgs/Path.h>
#include <ros/publisher.h>
#include <tf2_ros/transform_broadcaster.h>

#include "flowfusion/pipeline/result_sink.h"
#include "flowfusion/ros/frame_intake.h"

namespace ff::rosnode {

struct Publishers {
  ros::Publisher odometry, path, mask, cloud;
  tf2_ros::TransformBroadcaster* tf = nullptr;  // null: ~publish_tf false
};

class PublisherSink : public ResultSink {
 public:
  PublisherSink(const Publishers& publishers, const NodeParams& params, const FrameIntake& intake);

  void begin(const RunInfo& info) override;
  void frame(const RgbdFrame& frame, const FrameResult& result) override;
  // The map, when ~map_period_s passed since it was published last (the run's thread, between frames).
  void publishMapWhenDue(const FlowFusionSystem& system);
  // The run's live figures after its last frame (any thread).
  LiveFigures figures() const;

 private:
  const Publishers& publishers_;
  const NodeParams& params_;
  const FrameIntake& intake_;
  const FrameSource* source_ = nullptr;  // its raw pixels
  const LiveFigures* live_ = nullptr;
  nav_msgs::Path path_;
  ColorHeader last_;  // of the last frame published
  std::chrono::steady_clock::time_point map_published_{};
  mutable std::mutex figures_mutex_;
  LiveFigures figures_;
};

}  // namespace ff::rosnode

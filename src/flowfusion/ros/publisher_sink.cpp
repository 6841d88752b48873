#include "flowfusion/ros/publisher_sink.h"

#include <cstring>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

namespace ff::rosnode {

namespace {

geometry_msgs::Pose poseOf(const SE3& T) {
  const Eigen::Quaterniond q(T.rotation());
  geometry_msgs::Pose p;
  p.position.x = T.translation().x();
  p.position.y = T.translation().y();
  p.position.z = T.translation().z();
  p.orientation.x = q.x();
  p.orientation.y = q.y();
  p.orientation.z = q.z();
  p.orientation.w = q.w();
  return p;
}

sensor_msgs::PointField field(const std::string& name, uint32_t offset) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  return f;
}

// x, y, z in metres and rgb packed as PCL does (0x00RRGGBB in the bits of a float32).
sensor_msgs::PointCloud2 cloudOf(const MapPoints& points, const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 c;
  c.header = header;
  c.height = 1;
  c.width = static_cast<uint32_t>(points.positions.size());
  c.fields = {field("x", 0), field("y", 4), field("z", 8), field("rgb", 12)};
  c.is_bigendian = false;
  c.point_step = 16;
  c.row_step = c.point_step * c.width;
  c.is_dense = true;
  c.data.resize(c.row_step);
  for (size_t i = 0; i < points.positions.size(); ++i) {
    uint8_t* p = &c.data[i * c.point_step];
    std::memcpy(p, points.positions[i].data(), 12);
    const cv::Vec3b& bgr = points.colors[i];
    const uint32_t rgb = uint32_t(bgr[2]) << 16 | uint32_t(bgr[1]) << 8 | uint32_t(bgr[0]);
    std::memcpy(p + 12, &rgb, 4);
  }
  return c;
}

}  // namespace

PublisherSink::PublisherSink(const Publishers& publishers, const NodeParams& params, const FrameIntake& intake)
    : publishers_(publishers), params_(params), intake_(intake) {}

void PublisherSink::begin(const RunInfo& info) {
  source_ = info.frames;
  live_ = info.live;
  path_.header.frame_id = params_.map_frame;
}

void PublisherSink::frame(const RgbdFrame& frame, const FrameResult& result) {
  last_ = intake_.headerOf(frame.timestamp).value_or(ColorHeader{ros::Time(frame.timestamp), ""});
  const std::string camera_frame =
      !params_.camera_frame.empty() ? params_.camera_frame : !last_.frame_id.empty() ? last_.frame_id : "camera";
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = last_.stamp;
  pose.header.frame_id = params_.map_frame;
  pose.pose = poseOf(result.T_world_cam);
  if (publishers_.odometry.getNumSubscribers() > 0) {
    nav_msgs::Odometry odometry;
    odometry.header = pose.header;
    odometry.child_frame_id = camera_frame;
    odometry.pose.pose = pose.pose;
    publishers_.odometry.publish(odometry);
  }
  if (publishers_.tf) {
    geometry_msgs::TransformStamped t;
    t.header = pose.header;
    t.child_frame_id = camera_frame;
    t.transform.translation.x = pose.pose.position.x;
    t.transform.translation.y = pose.pose.position.y;
    t.transform.translation.z = pose.pose.position.z;
    t.transform.rotation = pose.pose.orientation;
    publishers_.tf->sendTransform(t);
  }
  path_.header.stamp = last_.stamp;
  path_.poses.push_back(pose);
  if (publishers_.path.getNumSubscribers() > 0) publishers_.path.publish(path_);
  if (publishers_.mask.getNumSubscribers() > 0) {
    const cv::Mat raw = source_ ? source_->toRawPixels(result.dynamic_mask) : result.dynamic_mask;
    sensor_msgs::Image mask;
    mask.header.stamp = last_.stamp;
    mask.header.frame_id = last_.frame_id;
    mask.height = raw.rows;
    mask.width = raw.cols;
    mask.encoding = "mono8";
    mask.step = raw.cols;
    mask.data.resize(size_t(raw.rows) * raw.cols);
    for (int y = 0; y < raw.rows; ++y) std::memcpy(&mask.data[size_t(y) * raw.cols], raw.ptr<uint8_t>(y), raw.cols);
    publishers_.mask.publish(mask);
  }
  if (live_) {
    std::lock_guard lock(figures_mutex_);
    figures_ = *live_;
  }
}

void PublisherSink::publishMapWhenDue(const FlowFusionSystem& system) {
  if (params_.map_period_s <= 0 || publishers_.cloud.getNumSubscribers() == 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - map_published_ < std::chrono::duration<double>(params_.map_period_s)) return;
  const StaticMap* map = system.map();
  if (!map) return;
  map_published_ = now;
  std_msgs::Header header;
  header.stamp = last_.stamp;
  header.frame_id = params_.map_frame;
  publishers_.cloud.publish(cloudOf(map->points(), header));
}

LiveFigures PublisherSink::figures() const {
  std::lock_guard lock(figures_mutex_);
  return figures_;
}

}  // namespace ff::rosnode

#include "flowfusion/ros/ros_node.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/synchronizer.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <set>

#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/ros/live_session.h"

namespace ff::rosnode {

namespace {

using sensor_msgs::CameraInfo;
using sensor_msgs::Image;
using ColorDepth = message_filters::sync_policies::ApproximateTime<Image, Image>;
using ColorDepthInfo = message_filters::sync_policies::ApproximateTime<Image, Image, CameraInfo>;

// The TUM RGB-D names; RealSense and OpenNI drivers' by remapping (README's launch files).
constexpr const char* kColorTopic = "/camera/rgb/image_color";
constexpr const char* kDepthTopic = "/camera/depth/image";
constexpr const char* kInfoTopic = "/camera/rgb/camera_info";
constexpr uint32_t kSubscriberQueue = 5;  // messages per topic roscpp holds while a callback runs
constexpr uint32_t kSyncQueue = 10;       // messages per topic the approximate-time policy matches among

std::atomic<int> g_signal{0};

void onSignal(int signal) {
  g_signal = signal;
  ros::requestShutdown();
}

std::string shutdownReason() {
  if (g_signal == SIGINT) return "interrupted (SIGINT)";
  if (g_signal == SIGTERM) return "terminated (SIGTERM)";
  return "ROS shut down (rosnode kill or the master)";
}

class RosNode {
 public:
  explicit RosNode(const RosNodeOptions& options);
  // Until ROS shuts down; then the run stops, written marked partial into ~save_dir when it is set.
  void spin();

 private:
  void subscribe();
  void onFrames(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth,
                const sensor_msgs::CameraInfoConstPtr& info);
  void onColorDepth(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth) {
    onFrames(color, depth, nullptr);
  }
  bool onSave(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  bool onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  std::shared_ptr<LiveSession> session();

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  FrameIntake intake_;
  tf2_ros::TransformBroadcaster tf_;
  Publishers publishers_;
  message_filters::Subscriber<Image> color_, depth_;
  message_filters::Subscriber<CameraInfo> info_;
  std::unique_ptr<message_filters::Synchronizer<ColorDepth>> sync_;
  std::unique_ptr<message_filters::Synchronizer<ColorDepthInfo>> sync_info_;
  ros::CallbackQueue service_queue_;  // services on their own thread: a save does not hold up the images
  ros::ServiceServer save_, reset_;
  diagnostic_updater::Updater diagnostics_;
  ros::Timer diagnostics_timer_;
  std::mutex mutex_;  // the members below and the intake
  std::shared_ptr<LiveSession> session_;
  size_t received_ = 0, refused_ = 0;
  std::string last_refusal_;
  std::set<std::string> logged_;
};

RosNode::RosNode(const RosNodeOptions& options)
    : pnh_("~"), params_(readNodeParams(pnh_, options)), intake_(params_), diagnostics_(nh_, pnh_) {
  publishers_.odometry = pnh_.advertise<nav_msgs::Odometry>("odometry", 10);
  publishers_.path = pnh_.advertise<nav_msgs::Path>("path", 1);
  publishers_.mask = pnh_.advertise<Image>("mask", 10);
  publishers_.cloud = pnh_.advertise<sensor_msgs::PointCloud2>("static_cloud", 1);
  if (params_.publish_tf) publishers_.tf = &tf_;
  subscribe();
  ros::NodeHandle services("~");
  services.setCallbackQueue(&service_queue_);
  save_ = services.advertiseService("save", &RosNode::onSave, this);
  reset_ = services.advertiseService("reset", &RosNode::onReset, this);
  diagnostics_.setHardwareID("flowfusion");
  diagnostics_.add("live", this, &RosNode::diagnose);
  diagnostics_timer_ = nh_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) { diagnostics_.update(); });
}

void RosNode::subscribe() {
  color_.subscribe(nh_, kColorTopic, kSubscriberQueue);
  depth_.subscribe(nh_, kDepthTopic, kSubscriberQueue);
  const ros::Duration slop(params_.sync_slop_s);
  if (params_.camera) {
    sync_ = std::make_unique<message_filters::Synchronizer<ColorDepth>>(ColorDepth(kSyncQueue), color_, depth_);
    sync_->setMaxIntervalDuration(slop);
    sync_->registerCallback(&RosNode::onColorDepth, this);
    ROS_INFO_STREAM("flowfusion: colour " << color_.getTopic() << ", depth " << depth_.getTopic() << ", camera given");
    return;
  }
  info_.subscribe(nh_, kInfoTopic, kSubscriberQueue);
  sync_info_ = std::make_unique<message_filters::Synchronizer<ColorDepthInfo>>(ColorDepthInfo(kSyncQueue), color_,
                                                                                depth_, info_);
  sync_info_->setMaxIntervalDuration(slop);
  sync_info_->registerCallback(&RosNode::onFrames, this);
  ROS_INFO_STREAM("flowfusion: colour " << color_.getTopic() << ", depth " << depth_.getTopic() << ", camera info "
                                        << info_.getTopic());
}

void RosNode::onFrames(const sensor_msgs::ImageConstPtr& color, const sensor_msgs::ImageConstPtr& depth,
                       const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard lock(mutex_);
  ++received_;
  try {
    RgbdFrame frame = intake_.take(*color, *depth, info.get());
    if (!session_ || session_->ended()) session_ = std::make_shared<LiveSession>(params_, intake_, publishers_);
    session_->offer(std::move(frame));
  } catch (const InputError& e) {
    ++refused_;
    last_refusal_ = e.what();
    const bool stamps = dynamic_cast<const StampsGoingBack*>(&e) != nullptr;
    if (logged_.insert(stamps ? "stamps going back" : last_refusal_).second)
      ROS_ERROR_STREAM("flowfusion: frame refused: " << last_refusal_ << " (logged once; diagnostics count them all)");
  }
}

std::shared_ptr<LiveSession> RosNode::session() {
  std::lock_guard lock(mutex_);
  return session_;
}

bool RosNode::onSave(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  try {
    const std::shared_ptr<LiveSession> s = session();
    if (!s) throw InputError("no frame processed yet");
    response.message = s->save();
    response.success = true;
  } catch (const std::exception& e) {
    response.message = e.what();
    response.success = false;
  }
  ROS_INFO_STREAM("flowfusion: ~save: " << response.message);
  return true;
}

bool RosNode::onReset(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
  std::shared_ptr<LiveSession> old;
  {
    std::lock_guard lock(mutex_);
    old.swap(session_);
    intake_.reset();
  }
  if (old) old->stop("reset (~reset)", false);
  response.success = true;
  response.message = old ? "the run ended; the next frame starts a new one" : "no run to end";
  ROS_INFO_STREAM("flowfusion: ~reset: " << response.message);
  return true;
}

void RosNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard lock(mutex_);
  const LiveFigures f = session_ ? session_->figures() : LiveFigures{};
  if (refused_ > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%zu frames refused, last: %s", refused_,
                    last_refusal_.c_str());
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, session_ ? "running" : "waiting for frames");
  status.add("frames received", received_);
  status.add("frames refused", refused_);
  status.add("frames offered", f.frames_offered);
  status.add("frames processed", f.frames_processed);
  status.add("frames dropped", f.frames_dropped);
  status.add("latency ms p50", f.latency_ms_p50);
  status.add("latency ms p95", f.latency_ms_p95);
}

void RosNode::spin() {
  ros::AsyncSpinner services(1, &service_queue_);
  services.start();
  ros::spin();  // returns once ROS has shut down (its logging too)
  services.stop();
  std::shared_ptr<LiveSession> s = session();
  if (!s) return;
  const std::string reason = shutdownReason();
  std::fprintf(stderr, "flowfusion: %s; stopping the run after %zu frames\n", reason.c_str(), s->figures().frames_processed);
  s->stop(reason, !params_.save_dir.empty());
}

}  // namespace

int runRosNode(const RosNodeOptions& options) {
  commandLineConfig(options);
  if (!options.camera.empty()) parseCameraModel(options.camera);
  std::vector<std::string> args = {"flowfusion"};
  args.insert(args.end(), options.ros_arguments.begin(), options.ros_arguments.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  int argc = static_cast<int>(argv.size());
  ros::init(argc, argv.data(), "flowfusion", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  setOutputCommand("run");
  {
    RosNode node(options);
    node.spin();
  }
  ros::shutdown();
  return 0;
}

}  // namespace ff::rosnode

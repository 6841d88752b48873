// The ROS 1 node (`flowfusion ros`) against a real roscore, which the ctest fixture
// (tests/ros/roscore_fixture.sh) starts on 127.0.0.1 at a free port: a bag of a short synthetic
// dynamic sequence is played with `rosbag play -r 0.2`, the node's outputs recorded with `rosbag
// record` and compared with the offline run of the same bag: the same poses and masks (nothing is
// dropped at that rate), stamped with the colour images' stamps, on ~odometry, /tf and ~mask; the
// static cloud published; diagnostics counting every frame; ~save writes what `run` writes; SIGINT
// ends the node cleanly with a partial result. Bad parameters, a colour encoding the node cannot read
// and stamps going back keep it alive, each with one logged error; ~reset starts a new run; the
// README's launch files start it on the RealSense and OpenNI drivers' topics.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include "flowfusion/core/error.h"
#include "flowfusion/io/bag_source.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/run_output.h"
#include "testing/test_util.h"

#if defined(FLOWFUSION_HAVE_ROS_NODE) && defined(FLOWFUSION_ROS_TOOLS)
#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <opencv2/imgproc.hpp>

#include "flowfusion/io/ros_messages.h"
#endif

namespace fs = std::filesystem;

namespace ff {
namespace {

using testing::runFlowfusion;

#ifndef FLOWFUSION_HAVE_ROS_NODE

TEST(RosNode, ABuildWithoutTheNodeSaysHowToEnableIt) {
  const testing::CommandResult r = runFlowfusion("ros");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("scripts/install-deps.sh"), std::string::npos) << r.output;
  GTEST_SKIP() << "the ROS 1 node is not built (install the ROS 1 block of scripts/install-deps.sh); only its "
                  "message was checked";
}

#elif !defined(FLOWFUSION_ROS_TOOLS)

TEST(RosNode, NeedsTheRosTools) {
  GTEST_SKIP() << "roscore, rosbag or rosservice not found (Debian's ros-core): the node's tests did not run";
}

#else

using ImageMsg = ros1::ImageMsg;
using CameraInfoMsg = ros1::CameraInfoMsg;
using OdometryMsg = nav_msgs::Odometry_<ros1::RosAllocator<void>>;
using CloudMsg = sensor_msgs::PointCloud2_<ros1::RosAllocator<void>>;
using TfMsg = tf2_msgs::TFMessage_<ros1::RosAllocator<void>>;
using DiagnosticsMsg = diagnostic_msgs::DiagnosticArray_<ros1::RosAllocator<void>>;

constexpr int kFrames = 8;
constexpr double kDepthScale = 1000;  // the node's and bags' 16UC1 units per metre

// The master the fixture started, for this process and the commands it starts.
bool useFixtureMaster() {
  std::ifstream in(std::string(FLOWFUSION_ROS_FIXTURE_DIR) + "/master_uri");
  std::string uri;
  if (!(in >> uri)) return false;
  setenv("ROS_MASTER_URI", uri.c_str(), 1);
  setenv("ROS_IP", "127.0.0.1", 1);
  setenv("ROS_HOME", (std::string(FLOWFUSION_ROS_FIXTURE_DIR) + "/home").c_str(), 1);
  return true;
}

// A command running beside the test, its output in a log file.
class Process {
 public:
  Process(const std::vector<std::string>& argv, const fs::path& log) : log_(log) {
    pid_ = fork();
    if (pid_ == 0) {
      setpgid(0, 0);  // its own group: a wrapper (rosbag, roslaunch) is signalled with what it started
      FILE* out = std::fopen(log.c_str(), "w");
      dup2(fileno(out), 1);
      dup2(fileno(out), 2);
      std::vector<char*> args;
      for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execvp(args[0], args.data());
      _exit(127);
    }
  }
  ~Process() {
    if (pid_ > 0 && !exited_) {
      kill(-pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  bool running() {
    if (exited_) return false;
    int st = 0;
    if (waitpid(pid_, &st, WNOHANG) == pid_) {
      exited_ = true;
      status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    }
    return !exited_;
  }
  // Sends `signal` to its group and waits for the exit; its status (128 + signal when killed), -1 after 20 s.
  int stop(int signal) {
    kill(-pid_, signal);
    for (int i = 0; i < 200 && running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    return exited_ ? status_ : -1;
  }
  std::string log() const {
    std::ifstream in(log_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }

 private:
  fs::path log_;
  pid_t pid_ = -1;
  bool exited_ = false;
  int status_ = -1;
};

// Polls `check` every 100 ms for `seconds`.
bool eventually(const std::function<bool()>& check, double seconds) {
  for (int i = 0; i < seconds * 10; ++i) {
    if (check()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return check();
}

bool shellSays(const std::string& command, const std::string& text) {
  return testing::runShell(command).output.find(text) != std::string::npos;
}

ros::Time rosTime(double t) {
  const auto us = static_cast<int64_t>(std::llround(t * 1e6));
  return ros::Time(static_cast<uint32_t>(us / 1000000), static_cast<uint32_t>(us % 1000000) * 1000);
}

ImageMsg imageMsg(const cv::Mat& m, const std::string& encoding, const ros::Time& stamp) {
  ImageMsg msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = "camera_rgb_optical_frame";
  msg.height = m.rows;
  msg.width = m.cols;
  msg.encoding = encoding;
  msg.step = static_cast<uint32_t>(m.cols * m.elemSize());
  msg.data.assign(m.data, m.data + m.total() * m.elemSize());
  return msg;
}

// A synthetic dynamic sequence (320x240, one moving object) as a bag of what a driver publishes:
// colour (rgb8, or `color_encoding` with the same bytes), depth 16UC1 in millimetres and the colour
// CameraInfo with every frame. Seed 2's object is segmented from the second frame on (seed 3's
// only in the last two of the eight, and with scores.long_baseline_frames in none; at 160x120 the
// DIS medium preset, its flow at 80x60, loses it after the second frame).
std::vector<ros::Time> writeBag(const std::string& path, const std::string& color_encoding = "rgb8") {
  synth::SynthConfig c;
  c.seed = 2;
  c.frames = kFrames;
  c.width = 320;
  c.height = 240;
  c.objects = 1;
  const synth::SyntheticScene scene(c);
  const CameraIntrinsics& k = scene.camera();
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  std::vector<ros::Time> stamps;
  for (int i = 0; i < kFrames; ++i) {
    const RgbdFrame f = scene.render(i).frame;
    const ros::Time t = rosTime(scene.timestamp(i));
    CameraInfoMsg info;
    info.header.stamp = t;
    info.width = k.width;
    info.height = k.height;
    info.distortion_model = "plumb_bob";
    info.D.assign(5, 0.0);
    info.K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
    bag.write("/camera/rgb/camera_info", t, info);
    cv::Mat rgb, mm;
    cv::cvtColor(f.color, rgb, cv::COLOR_BGR2RGB);
    f.depth.convertTo(mm, CV_16U, kDepthScale);
    bag.write("/camera/rgb/image_color", t, imageMsg(rgb, color_encoding, t));
    bag.write("/camera/depth/image", t, imageMsg(mm, "16UC1", t));
    stamps.push_back(t);
  }
  bag.close();
  return stamps;
}

template <class T>
std::vector<boost::shared_ptr<T>> messages(const std::string& bag_path, const std::string& topic) {
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  std::vector<boost::shared_ptr<T>> out;
  for (const rosbag::MessageInstance& m : view)
    if (auto msg = m.instantiate<T>()) out.push_back(msg);
  return out;
}

std::string fileText(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class RosNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!useFixtureMaster()) GTEST_SKIP() << "no roscore: run through ctest, whose fixture RosCore.Start starts one";
    testing::runShell("rosparam delete /flowfusion");  // private parameters an earlier test's node left
  }
  // The node with `args`, once its services are up.
  std::unique_ptr<Process> startNode(const std::vector<std::string>& args) {
    std::vector<std::string> argv = {FLOWFUSION_APP_PATH, "ros", "__name:=flowfusion"};
    argv.insert(argv.end(), args.begin(), args.end());
    auto node = std::make_unique<Process>(argv, tmp.path() / "node.log");
    EXPECT_TRUE(eventually([] { return shellSays("rosservice list", "/flowfusion/reset"); }, 30)) << node->log();
    return node;
  }
  void play(const std::string& bag) {
    const testing::CommandResult r = testing::runShell("rosbag play -q -r 0.2 --wait-for-subscribers " + bag);
    EXPECT_EQ(r.status, 0) << r.output;
  }
  testing::TempDir tmp;
};

TEST_F(RosNodeTest, PublishesTheOfflineRunsPosesAndMasksAndSavesWhatRunWrites) {
  const std::string bag = (tmp.path() / "synth.bag").string();
  const std::vector<ros::Time> stamps = writeBag(bag);
  BagSource offline_source(bag, SequenceOptions{});
  const testing::RunOutput offline = testing::runOn(offline_source);
  ASSERT_EQ(offline.poses.size(), size_t(kFrames));

  const fs::path saved = tmp.path() / "saved", recorded = tmp.path() / "out.bag";
  // Without the live frame budget and with the offline flow preset (liveDefaults), so that every
  // frame is computed as offline whatever the load.
  const fs::path offline_config = tmp.path() / "offline.json";
  std::ofstream(offline_config) << R"({"pipeline": {"budget_ms": 0}, "flow": {"dis_preset": "medium"}})";
  auto node = startNode({"_save_dir:=" + saved.string(), "_map_period_s:=0.05", "_config:=" + offline_config.string()});
  const std::vector<std::string> topics = {"/flowfusion/odometry", "/flowfusion/mask", "/flowfusion/static_cloud",
                                           "/flowfusion/path", "/diagnostics", "/tf"};
  std::vector<std::string> record = {"rosbag", "record", "-O", recorded.string(), "__name:=recorder"};
  record.insert(record.end(), topics.begin(), topics.end());
  Process recorder(record, tmp.path() / "record.log");
  for (const std::string& t : topics)
    ASSERT_TRUE(eventually([&] { return shellSays("rostopic info " + t, "/recorder"); }, 20)) << t;
  play(bag);

  // Every frame processed: ~save then writes all of them.
  const fs::path trajectory = saved / "trajectory.txt";
  const auto lines = [&] {
    std::ifstream in(trajectory);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) n += !line.empty() && line[0] != '#';
    return n;
  };
  ASSERT_TRUE(eventually(
      [&] { return shellSays("rosservice call /flowfusion/save", "success: True") && lines() == kFrames; }, 20))
      << node->log();
  const fs::path run_dir = tmp.path() / "run";
  ASSERT_EQ(runFlowfusion("run " + bag + " --out " + run_dir.string() + " --quiet").status, 0);
  EXPECT_EQ(fileText(trajectory), fileText(run_dir / "trajectory.txt"));
  for (const auto& e : fs::directory_iterator(run_dir / "masks"))
    EXPECT_EQ(fileText(e.path()), fileText(saved / "masks" / e.path().filename())) << e.path();
  EXPECT_TRUE(fs::exists(saved / "map_points.ply"));

  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // a diagnostics message after the last frame
  EXPECT_EQ(recorder.stop(SIGINT), 0) << recorder.log();
  EXPECT_EQ(node->stop(SIGINT), 0) << node->log();
  EXPECT_EQ(node->log().find("ERROR"), std::string::npos) << node->log();
  EXPECT_NE(node->log().find("wrote 8 frames into " + saved.string() + " (partial: interrupted (SIGINT))"),
            std::string::npos)
      << node->log();
  const std::string summary = fileText(saved / "summary.json");
  EXPECT_NE(summary.find("\"complete\": false"), std::string::npos) << summary;
  EXPECT_NE(summary.find("interrupted (SIGINT)"), std::string::npos) << summary;

  const auto odometry = messages<OdometryMsg>(recorded.string(), "/flowfusion/odometry");
  ASSERT_EQ(odometry.size(), size_t(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    const auto& p = odometry[i]->pose.pose;
    const SE3& T = offline.poses[i].second;
    EXPECT_EQ(odometry[i]->header.stamp, stamps[i]);
    EXPECT_EQ(std::string(odometry[i]->header.frame_id.begin(), odometry[i]->header.frame_id.end()), "map");
    EXPECT_EQ(std::string(odometry[i]->child_frame_id.begin(), odometry[i]->child_frame_id.end()),
              "camera_rgb_optical_frame");
    const Eigen::Quaterniond q(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    EXPECT_LT((Eigen::Vector3d(p.position.x, p.position.y, p.position.z) - T.translation()).norm(), 1e-9) << i;
    EXPECT_LT((q.toRotationMatrix() - T.rotation()).cwiseAbs().maxCoeff(), 1e-9) << i;
  }
  const auto tf = messages<TfMsg>(recorded.string(), "/tf");
  ASSERT_EQ(tf.size(), size_t(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(tf[i]->transforms.size(), 1u);
    const auto& t = tf[i]->transforms[0];
    EXPECT_EQ(t.header.stamp, stamps[i]);
    EXPECT_EQ(std::string(t.child_frame_id.begin(), t.child_frame_id.end()), "camera_rgb_optical_frame");
    EXPECT_EQ(t.transform.translation.x, odometry[i]->pose.pose.position.x);
  }
  const auto masks = messages<ImageMsg>(recorded.string(), "/flowfusion/mask");
  ASSERT_EQ(masks.size(), size_t(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    EXPECT_EQ(masks[i]->header.stamp, stamps[i]);
    EXPECT_EQ(masks[i]->encoding, "mono8");
    const cv::Mat mask(int(masks[i]->height), int(masks[i]->width), CV_8U, masks[i]->data.data(), masks[i]->step);
    EXPECT_EQ(cv::norm(mask, offline.masks[i], cv::NORM_INF), 0) << "frame " << i;
  }
  EXPECT_GT(cv::countNonZero(offline.masks.back()), 0);  // the object is in the masks
  const auto clouds = messages<CloudMsg>(recorded.string(), "/flowfusion/static_cloud");
  ASSERT_FALSE(clouds.empty());
  EXPECT_GT(clouds.back()->width, 1000u);
  EXPECT_EQ(clouds.back()->header.frame_id, "map");
  EXPECT_EQ(clouds.back()->point_step, 16u);
  // The last diagnostics: every frame received and processed, none dropped.
  std::map<std::string, std::string> figures;
  for (const auto& array : messages<DiagnosticsMsg>(recorded.string(), "/diagnostics"))
    for (const auto& status : array->status)
      if (std::string(status.name.begin(), status.name.end()).find("flowfusion") != std::string::npos)
        for (const auto& kv : status.values)
          figures[std::string(kv.key.begin(), kv.key.end())] = std::string(kv.value.begin(), kv.value.end());
  EXPECT_EQ(figures["frames received"], std::to_string(kFrames));
  EXPECT_EQ(figures["frames processed"], std::to_string(kFrames));
  EXPECT_EQ(figures["frames dropped"], "0");
  EXPECT_EQ(figures["frames refused"], "0");
}

size_t occurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Bad parameters, a colour encoding the node cannot read and stamps going back (a bag played again):
// each logged once with its reason, the node running on; after ~reset the bag is a new run.
TEST_F(RosNodeTest, BadParametersAndMessagesAreLoggedOnceAndTheNodeRunsOn) {
  const std::string yuv = (tmp.path() / "yuv.bag").string(), good = (tmp.path() / "good.bag").string();
  writeBag(yuv, "yuv422");
  writeBag(good);
  auto node = startNode({"_depth_scale:=-3", "_map_period_s:=soon", "_set:=odometry.no_such_key=1"});
  play(yuv);
  EXPECT_TRUE(shellSays("rosservice call /flowfusion/save", "no frame processed yet"));
  play(good);
  play(good);
  EXPECT_TRUE(shellSays("rosservice call /flowfusion/reset", "the run ended; the next frame starts a new one"));
  play(good);  // after ~reset, a new run of the same frames
  EXPECT_TRUE(node->running()) << node->log();
  EXPECT_EQ(node->stop(SIGINT), 0) << node->log();
  const std::string log = node->log();
  EXPECT_EQ(occurrences(log, "ERROR"), 5u) << log;
  EXPECT_EQ(occurrences(log, "parameter ~depth_scale ignored: must be 16UC1 depth units per metre"), 1u) << log;
  EXPECT_EQ(occurrences(log, "parameter ~map_period_s ignored"), 1u) << log;
  EXPECT_EQ(occurrences(log, "parameter ~set odometry.no_such_key=1 ignored"), 1u) << log;
  EXPECT_EQ(occurrences(log, "colour encoding 'yuv422' is not one of rgb8"), 1u) << log;
  EXPECT_EQ(occurrences(log, "(stamps going back"), 1u) << log;
  EXPECT_NE(log.find("stopping the run after 8 frames"), std::string::npos) << log;
}

// The README's launch files start the node (through examples/ros/flowfusion_node) on each driver's topics.
TEST_F(RosNodeTest, TheLaunchFilesStartTheNodeOnTheDriversTopics) {
  setenv("ROS_PACKAGE_PATH", FLOWFUSION_ROS_EXAMPLES, 1);
  setenv("FLOWFUSION", FLOWFUSION_APP_PATH, 1);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"realsense.launch", "/camera/aligned_depth_to_color/image_raw"}, {"openni.launch", "/camera/depth_registered/image_raw"}};
  for (const auto& [launch, depth_topic] : cases) {
    Process roslaunch({"roslaunch", "flowfusion_ros", launch}, tmp.path() / (launch + ".log"));
    EXPECT_TRUE(eventually([&] { return shellSays("rostopic info " + depth_topic, "/flowfusion"); }, 30))
        << roslaunch.log();
    EXPECT_EQ(roslaunch.stop(SIGINT), 0) << roslaunch.log();
    EXPECT_EQ(roslaunch.log().find("ERROR"), std::string::npos) << roslaunch.log();
  }
}

#endif

}  // namespace
}  // namespace ff

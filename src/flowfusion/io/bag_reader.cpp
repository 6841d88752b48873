#include "flowfusion/io/bag_reader.h"

#include <algorithm>
#include <filesystem>

#include "flowfusion/core/error.h"
#include "flowfusion/io/dataset_layout.h"
#include "flowfusion/io/ros_images.h"
#include "flowfusion/io/tum_text.h"

namespace ff {

namespace {

// Looked for in this order when no topic is given (TUM RGB-D, OpenNI, RealSense).
const std::vector<std::string> kColorTopics = {"/camera/rgb/image_color", "/camera/color/image_raw",
                                               "/camera/rgb/image_raw", "/camera/rgb/image_rect_color"};
const std::vector<std::string> kDepthTopics = {"/camera/depth/image", "/camera/aligned_depth_to_color/image_raw",
                                               "/camera/depth_registered/image_raw", "/camera/depth/image_raw"};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool isImage(RosType t) { return t == RosType::kImage || t == RosType::kCompressedImage; }

// InputError unless the options' depth scale is usable, before anything is read.
void checkOptions(const SequenceOptions& options) { checkDepthScale(options.bag.depth_scale, "--depth-scale"); }

}  // namespace

bool isRos2BagPath(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string ext = fs::path(path).extension().string();
  std::error_code ec;
  return ext == ".mcap" || ext == ".db3" || (fs::is_directory(path, ec) && fs::exists(fs::path(path) / "metadata.yaml", ec));
}

std::unique_ptr<RosRecording> openRosRecording(const std::string& path) {
  return isRos2BagPath(path) ? openRos2Recording(path) : openRos1Recording(path);
}

struct BagReader::Impl {
  std::string path;
  SequenceOptions options;
  std::unique_ptr<RosRecording> recording;
  std::vector<RosTopic> topics;
  std::string color_topic, depth_topic, color_type, depth_type;
  CameraModel camera;
  std::vector<double> color_stamps, depth_stamps;  // s, header stamps in the bag's order
  std::vector<std::pair<size_t, size_t>> pairs;  // (colour message, depth message)

  [[noreturn]] void fail(const std::string& message) const { throw InputError(path + ": " + message); }

  std::string typeOf(const std::string& topic) const;
  std::string chooseTopic(const std::string& given, const std::vector<std::string>& known, bool depth,
                          const std::string& what, const std::string& flag) const;
  void pickTopics();
  void readStamps();
  void readCamera();
  std::string cameraInfoTopic() const;
  std::string listing() const;
};

std::string BagReader::Impl::listing() const {
  std::string out;
  for (const RosTopic& t : topics)
    if (out.find(" " + t.name + " (") == std::string::npos) out += " " + t.name + " (" + t.datatype + ")";
  return out.empty() ? " none" : out;
}

// A topic's image message type, "" when it has none; a topic recorded with both image types is
// refused by name.
std::string BagReader::Impl::typeOf(const std::string& topic) const {
  std::string type;
  for (const RosTopic& t : topics) {
    if (t.name != topic || !isImage(t.type)) continue;
    if (type.empty()) type = t.datatype;
    else if (t.datatype != type)
      fail(topic + ": holds both " + type + " and " + t.datatype + " messages; a colour or depth topic must carry "
           "one message type (choose another topic with --rgb-topic / --depth-topic)");
  }
  return type;
}

std::string BagReader::Impl::chooseTopic(const std::string& given, const std::vector<std::string>& known, bool depth,
                                         const std::string& what, const std::string& flag) const {
  if (!given.empty()) {
    if (typeOf(given).empty())
      fail("no sensor_msgs/Image or CompressedImage messages on " + flag + " " + given + "; topics:" + listing());
    return given;
  }
  for (const auto& k : known)
    if (!typeOf(k).empty()) return k;
  std::vector<std::string> candidates;
  bool any_image = false;
  for (const RosTopic& t : topics) {
    if (!isImage(t.type)) continue;
    any_image = true;
    if ((lower(t.name).find("depth") != std::string::npos) == depth &&
        std::find(candidates.begin(), candidates.end(), t.name) == candidates.end())
      candidates.push_back(t.name);
  }
  if (candidates.size() == 1) return candidates[0];
  if (!any_image) fail("no image topics (sensor_msgs/Image or CompressedImage); topics:" + listing());
  fail(candidates.empty() ? "no " + what + " image topic found; give it with " + flag + "; topics:" + listing()
                          : std::to_string(candidates.size()) + " candidate " + what + " topics; choose one with " +
                                flag + "; topics:" + listing());
}

void BagReader::Impl::pickTopics() {
  topics = recording->topics();
  color_topic = chooseTopic(options.bag.rgb_topic, kColorTopics, false, "colour", "--rgb-topic");
  depth_topic = chooseTopic(options.bag.depth_topic, kDepthTopics, true, "depth", "--depth-topic");
  if (color_topic == depth_topic) fail("colour and depth topics are the same (" + color_topic + ")");
  color_type = typeOf(color_topic);
  depth_type = typeOf(depth_topic);
}

// Each image message's header stamp, its encoding checked: one pass over both topics in the bag's
// order (a compressed chunk holding a colour and a depth message is decompressed once).
void BagReader::Impl::readStamps() {
  recording->scanImages({color_topic, depth_topic}, [&](size_t slot, const RosImage& m) {
    const bool is_color = slot == 0;
    const std::string& topic = is_color ? color_topic : depth_topic;
    std::vector<double>& out = is_color ? color_stamps : depth_stamps;
    const double t = rosSeconds(m.stamp);
    if (const std::string problem = rosEncodingProblem(m.compressed, m.encoding, is_color ? RosImageKind::kColor : RosImageKind::kDepth);
        !problem.empty())
      fail(topic + " message " + std::to_string(out.size()) + ": " + problem);
    if (!out.empty() && !(t > out.back()))
      fail(topic + " message " + std::to_string(out.size()) + ": header stamp " + timestampName(t) +
           " is not after the previous message's " + timestampName(out.back()) +
           " (stamps must increase in the bag's order)");
    out.push_back(t);
  });
}

// CameraInfo beside the colour topic, else the bag's only CameraInfo topic.
std::string BagReader::Impl::cameraInfoTopic() const {
  const std::string sibling = color_topic.substr(0, color_topic.rfind('/') + 1) + "camera_info";
  std::vector<std::string> infos;
  for (const RosTopic& t : topics)
    if (t.type == RosType::kCameraInfo && std::find(infos.begin(), infos.end(), t.name) == infos.end())
      infos.push_back(t.name);
  if (std::find(infos.begin(), infos.end(), sibling) != infos.end()) return sibling;
  if (infos.size() == 1) return infos[0];
  fail("no camera intrinsics: no sensor_msgs/CameraInfo on " + sibling +
       (infos.empty() ? std::string() : " (and " + std::to_string(infos.size()) + " other CameraInfo topics)") +
       "; give --camera fr1|fr2|fr3|fx,fy,cx,cy,width,height");
}

void BagReader::Impl::readCamera() {
  if (!options.camera.empty()) {
    camera = parseCameraModel(options.camera);
    return;
  }
  if (const auto named = datasetCameraFromName(std::filesystem::path(path).stem().string())) {
    camera = named->camera;
    return;
  }
  const std::string topic = cameraInfoTopic();
  const std::optional<RosCameraInfo> msg = recording->firstCameraInfo(topic);
  if (!msg) fail(topic + ": no CameraInfo message; give --camera");
  camera = cameraModelFromInfo(*msg, path + ": " + topic);
}

BagReader::BagReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BagReader::BagReader(BagReader&&) noexcept = default;
BagReader& BagReader::operator=(BagReader&&) noexcept = default;
BagReader::~BagReader() = default;

BagReader BagReader::open(const std::string& path, const SequenceOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  impl->recording = openRosRecording(path);
  checkOptions(options);
  impl->pickTopics();
  impl->readStamps();
  impl->readCamera();
  const std::vector<double>& tc = impl->color_stamps;
  const std::vector<double>& td = impl->depth_stamps;
  impl->pairs = associate(tc, td, options.max_time_diff, StampLimit::kInclusive);
  if (impl->pairs.empty())
    impl->fail("no colour message on " + impl->color_topic + " has a depth message on " + impl->depth_topic +
               " within " + std::to_string(options.max_time_diff) + " s (" + std::to_string(tc.size()) + " colour, " +
               std::to_string(td.size()) + " depth messages; check their header stamps)");
  return BagReader(std::move(impl));
}

size_t BagReader::size() const { return impl_->pairs.size(); }
const CameraModel& BagReader::camera() const { return impl_->camera; }
const std::string& BagReader::path() const { return impl_->path; }
const std::string& BagReader::colorTopic() const { return impl_->color_topic; }
const std::string& BagReader::depthTopic() const { return impl_->depth_topic; }

BagFrame BagReader::read(size_t i) {
  Impl& d = *impl_;
  const auto [ci, di] = d.pairs.at(i);
  BagFrame f;
  f.timestamp = d.color_stamps[ci];
  f.depth_timestamp = d.depth_stamps[di];
  f.name = d.path + ":" + d.color_topic + "#" + std::to_string(ci);
  const std::string depth_name = d.path + ":" + d.depth_topic + "#" + std::to_string(di);
  f.bgr8 = decodeRosColor(d.recording->image(0, ci), f.name, d.camera.intrinsics);
  f.depth = decodeRosDepth(d.recording->image(1, di), depth_name, d.camera.intrinsics, d.options.bag.depth_scale,
                           f.depth_scale);
  return f;
}

}  // namespace ff

#include "flowfusion/io/bag_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/io/dataset_layout.h"
#include "flowfusion/io/tum_text.h"

namespace ff {

namespace {

// Looked for in this order when no topic is given (TUM RGB-D, OpenNI, RealSense).
const std::vector<std::string> kColorTopics = {"/camera/rgb/image_color", "/camera/color/image_raw",
                                               "/camera/rgb/image_raw", "/camera/rgb/image_rect_color"};
const std::vector<std::string> kDepthTopics = {"/camera/depth/image", "/camera/aligned_depth_to_color/image_raw",
                                               "/camera/depth_registered/image_raw", "/camera/depth/image_raw"};

// The stamp as the decimal number it is ("sec.nnnnnnnnn" parsed), so that a stamp written to a
// TUM list with %.6f reads back as the same double.
double seconds(const RosStamp& t) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%lld.%09u", static_cast<long long>(t.sec), t.nsec);
  return std::strtod(buf, nullptr);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool isImage(RosType t) { return t == RosType::kImage || t == RosType::kCompressedImage; }

enum class Kind { kColor, kDepth };

// Why an encoding cannot be read as `kind`, or "" when it can.
std::string encodingProblem(bool compressed, const std::string& encoding, Kind kind) {
  const std::string e = lower(encoding);
  if (compressed) {
    if (e.find("compresseddepth") != std::string::npos)
      return "compressedDepth images are not supported (record the raw depth topic)";
    if (kind == Kind::kDepth) return "depth must be a raw sensor_msgs/Image (16UC1, mono16 or 32FC1)";
    if (e.find("png") == std::string::npos && e.find("jpeg") == std::string::npos &&
        e.find("jpg") == std::string::npos)
      return "compressed format '" + encoding + "' is not png or jpeg";
    return "";
  }
  if (kind == Kind::kColor) {
    if (e == "rgb8" || e == "bgr8" || e == "mono8" || e == "rgba8" || e == "bgra8") return "";
    return "colour encoding '" + encoding + "' is not one of rgb8, bgr8, mono8, rgba8, bgra8";
  }
  if (e == "16uc1" || e == "mono16" || e == "32fc1") return "";
  return "depth encoding '" + encoding + "' is not one of 16UC1, mono16, 32FC1";
}

// The pixels of a raw image message (rows `step` bytes apart), copied; InputError when the
// message holds fewer bytes than it declares.
cv::Mat wrapImage(const RosImage& m, int type, const std::string& name) {
  const size_t row = size_t(m.width) * CV_ELEM_SIZE(type);
  if (m.width == 0 || m.height == 0 || m.step < row || m.size < size_t(m.step) * m.height ||
      static_cast<long long>(m.width) * m.height > kMaxImagePixels)
    throw InputError(name + ": image message of " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                     " (step " + std::to_string(m.step) + ") holds " + std::to_string(m.size) + " bytes");
  cv::Mat view(int(m.height), int(m.width), type, const_cast<uint8_t*>(m.data), m.step);
  cv::Mat out = view.clone();
  if (m.big_endian && CV_ELEM_SIZE1(type) > 1) {
    // Multi-byte samples stored big-endian: reverse each sample's bytes.
    const size_t n = CV_ELEM_SIZE1(type);
    for (int y = 0; y < out.rows; ++y)
      for (uint8_t* p = out.ptr<uint8_t>(y); p < out.ptr<uint8_t>(y) + row; p += n) std::reverse(p, p + n);
  }
  return out;
}

cv::Mat toBgr(const cv::Mat& image, const std::string& name) {
  if (image.depth() != CV_8U) throw InputError(name + ": colour image must be 8-bit per channel");
  cv::Mat bgr;
  if (image.channels() == 1) cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  else if (image.channels() == 4) cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  else bgr = image;
  return bgr;
}

std::string sizeMismatch(const std::string& name, long long w, long long h, const CameraIntrinsics& c) {
  return name + ": image is " + std::to_string(w) + "x" + std::to_string(h) + ", the camera is " +
         std::to_string(c.width) + "x" + std::to_string(c.height);
}

void checkSize(const cv::Mat& image, const std::string& name, const CameraIntrinsics& c) {
  if (image.cols != c.width || image.rows != c.height) throw InputError(sizeMismatch(name, image.cols, image.rows, c));
}

// A compressed colour image decoded; a PNG declares its size before any pixel is decoded
// (image_file.h), so a wrong one is refused there.
cv::Mat decodeCompressed(const RosImage& m, const std::string& name, const CameraIntrinsics& c) {
  const uint8_t* d = m.data;
  if (m.size >= 24 && d[1] == 'P' && d[2] == 'N' && d[3] == 'G') {
    const auto be32 = [&](size_t at) {
      return uint32_t(d[at]) << 24 | uint32_t(d[at + 1]) << 16 | uint32_t(d[at + 2]) << 8 | uint32_t(d[at + 3]);
    };
    if (be32(16) != uint32_t(c.width) || be32(20) != uint32_t(c.height))
      throw InputError(sizeMismatch(name, be32(16), be32(20), c));
  }
  cv::Mat decoded;
  if (m.size > 0 && m.size < size_t(INT32_MAX)) {
    const cv::Mat bytes(1, int(m.size), CV_8U, const_cast<uint8_t*>(d));
    try {
      decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
    }
  }
  if (decoded.empty()) throw InputError(name + ": compressed image (" + m.encoding + ") does not decode");
  return toBgr(decoded, name);
}

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
  cv::Mat decodeColor(const RosImage& m, const std::string& name) const;
  cv::Mat decodeDepth(const RosImage& m, const std::string& name, double& scale) const;
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
    const double t = seconds(m.stamp);
    if (const std::string problem = encodingProblem(m.compressed, m.encoding, is_color ? Kind::kColor : Kind::kDepth);
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
  std::vector<double> v = {msg->k[0], msg->k[4], msg->k[2], msg->k[5], double(msg->width), double(msg->height)};
  const std::string& model = msg->distortion_model;
  const std::vector<double>& d = msg->d;
  bool distorted = false;
  for (double k : d) distorted = distorted || k != 0;
  if (distorted) {
    if (model != "plumb_bob" && !(model == "rational_polynomial" && d.size() >= 8 && d[5] == 0 && d[6] == 0 && d[7] == 0))
      fail(topic + ": distortion model '" + model + "' is not supported (plumb_bob); give --camera or --no-undistort");
    for (size_t k = 0; k < 5; ++k) v.push_back(k < d.size() ? d[k] : 0.0);
  }
  if (const auto problem = cameraValuesProblem(v)) fail(topic + ": " + *problem + "; give --camera");
  camera = cameraModelFromValues(v);
}

cv::Mat BagReader::Impl::decodeColor(const RosImage& m, const std::string& name) const {
  cv::Mat bgr;
  if (m.compressed) {
    bgr = decodeCompressed(m, name, camera.intrinsics);
  } else {
    const std::string e = lower(m.encoding);
    if (e == "rgb8") cv::cvtColor(wrapImage(m, CV_8UC3, name), bgr, cv::COLOR_RGB2BGR);
    else if (e == "bgr8") bgr = wrapImage(m, CV_8UC3, name);
    else if (e == "mono8") cv::cvtColor(wrapImage(m, CV_8UC1, name), bgr, cv::COLOR_GRAY2BGR);
    else if (e == "rgba8") cv::cvtColor(wrapImage(m, CV_8UC4, name), bgr, cv::COLOR_RGBA2BGR);
    else if (e == "bgra8") cv::cvtColor(wrapImage(m, CV_8UC4, name), bgr, cv::COLOR_BGRA2BGR);
    else throw InputError(name + ": " + encodingProblem(false, e, Kind::kColor));
  }
  checkSize(bgr, name, camera.intrinsics);
  return bgr;
}

cv::Mat BagReader::Impl::decodeDepth(const RosImage& m, const std::string& name, double& scale) const {
  const std::string e = lower(m.encoding);
  cv::Mat depth;
  if (m.compressed) {
    throw InputError(name + ": " + encodingProblem(true, e, Kind::kDepth));
  } else if (e == "16uc1" || e == "mono16") {
    depth = wrapImage(m, CV_16UC1, name);
    scale = options.bag.depth_scale;
  } else if (e == "32fc1") {
    depth = wrapImage(m, CV_32FC1, name);
    // No measurement is 0 in every stage; ROS drivers write NaN (and some +-inf or negatives).
    depth.forEach<float>([](float& d, const int*) {
      if (!std::isfinite(d) || d < 0) d = 0;
    });
    scale = 1;
  } else {
    throw InputError(name + ": " + encodingProblem(false, e, Kind::kDepth));
  }
  checkSize(depth, name, camera.intrinsics);
  return depth;
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
  f.bgr8 = d.decodeColor(d.recording->image(0, ci), f.name);
  f.depth = d.decodeDepth(d.recording->image(1, di), depth_name, f.depth_scale);
  return f;
}

}  // namespace ff

#include "flowfusion/io/bag_reader.h"

#include <stdexcept>

#include "flowfusion/core/error.h"

#ifdef FLOWFUSION_HAVE_ROSBAG

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/image_file.h"
#include "flowfusion/io/dataset_layout.h"
#include "flowfusion/io/ros_messages.h"
#include "flowfusion/io/tum_text.h"

namespace ff {

namespace {

using ros1::CameraInfoMsg;
using ros1::ImageMsg;
using CompressedMsg = ros1::CompressedImageMsg;

constexpr const char* kImageType = "sensor_msgs/Image";
constexpr const char* kCompressedType = "sensor_msgs/CompressedImage";
constexpr const char* kCameraInfoType = "sensor_msgs/CameraInfo";
// Looked for in this order when no topic is given (TUM RGB-D, OpenNI, RealSense).
const std::vector<std::string> kColorTopics = {"/camera/rgb/image_color", "/camera/color/image_raw",
                                               "/camera/rgb/image_raw", "/camera/rgb/image_rect_color"};
const std::vector<std::string> kDepthTopics = {"/camera/depth/image", "/camera/aligned_depth_to_color/image_raw",
                                               "/camera/depth_registered/image_raw", "/camera/depth/image_raw"};

template <class S>
std::string str(const S& s) {
  return std::string(s.begin(), s.end());
}

// The stamp as the decimal number it is ("sec.nnnnnnnnn" parsed), so that a stamp written to a
// TUM list with %.6f reads back as the same double.
double seconds(const ros::Time& t) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%u.%09u", t.sec, t.nsec);
  return std::strtod(buf, nullptr);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// The message as T; InputError when its definition (md5sum) is not the one T was generated from.
template <class T>
boost::shared_ptr<T> instantiate(const rosbag::MessageInstance& m, const std::string& where) {
  auto msg = m.instantiate<T>();
  if (!msg)
    throw InputError(where + ": " + m.getDataType() + " message whose definition (md5sum " + m.getMD5Sum() +
                     ") is not the one this build reads");
  return msg;
}

bool isImageTopic(const rosbag::ConnectionInfo& c) { return c.datatype == kImageType || c.datatype == kCompressedType; }

enum class Kind { kColor, kDepth };

// Why an encoding cannot be read as `kind`, or "" when it can.
std::string encodingProblem(const std::string& datatype, const std::string& encoding, Kind kind) {
  const std::string e = lower(encoding);
  if (datatype == kCompressedType) {
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

// Forward reading of one topic's messages by index; a read before the current position starts over.
class TopicCursor {
 public:
  TopicCursor(rosbag::Bag& bag, std::string topic) : bag_(&bag), topic_(std::move(topic)) { rewind(); }
  const rosbag::MessageInstance& at(size_t index) {
    if (index < pos_) rewind();
    for (; pos_ < index && it_ != view_->end(); ++pos_) ++it_;
    if (it_ == view_->end()) throw InputError(topic_ + ": message " + std::to_string(index) + " is missing");
    return *it_;
  }

 private:
  void rewind() {
    view_ = std::make_unique<rosbag::View>(*bag_, rosbag::TopicQuery(topic_));
    it_ = view_->begin();
    pos_ = 0;
  }
  rosbag::Bag* bag_;
  std::string topic_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  size_t pos_ = 0;
};

// InputError unless `path` is a regular file (a folder or a FIFO would only fail later as "corrupt").
void requireBagFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw InputError(path + ": bag file does not exist");
  if (fs::is_directory(st)) throw InputError(path + ": is a folder, not a ROS bag file (a TUM-layout folder must not end in .bag)");
  if (!fs::is_regular_file(st))
    throw InputError(path + ": is not a regular file (a FIFO, socket or device); a ROS bag is read from a file on disk");
}

}  // namespace

bool bagSupportBuilt() { return true; }

struct BagReader::Impl {
  std::string path;
  SequenceOptions options;
  rosbag::Bag bag;
  std::string color_topic, depth_topic, color_type, depth_type;
  CameraModel camera;
  std::vector<double> color_stamps, depth_stamps;  // s, header stamps in the bag's order
  std::vector<std::pair<size_t, size_t>> pairs;  // (colour message, depth message)
  std::unique_ptr<TopicCursor> color_cursor, depth_cursor;

  [[noreturn]] void fail(const std::string& message) const { throw InputError(path + ": " + message); }

  void pickTopics();
  void readStamps();
  void readCamera();
  cv::Mat decodeColor(const rosbag::MessageInstance& m, const std::string& name) const;
  cv::Mat decodeDepth(const rosbag::MessageInstance& m, const std::string& name, double& scale) const;
  void checkSize(const cv::Mat& image, const std::string& name) const;
};

void BagReader::Impl::pickTopics() {
  rosbag::View all(bag);
  std::vector<const rosbag::ConnectionInfo*> images;
  std::string listing;
  for (const rosbag::ConnectionInfo* c : all.getConnections()) {
    if (listing.find(" " + c->topic + " (") == std::string::npos)
      listing += " " + c->topic + " (" + c->datatype + ")";
    if (isImageTopic(*c)) images.push_back(c);
  }
  if (listing.empty()) listing = " none";
  // A topic's message type; a topic recorded with both image types is refused by name.
  const auto typeOf = [&](const std::string& topic) -> std::string {
    std::string type;
    for (const auto* c : images)
      if (c->topic == topic && type.empty()) type = c->datatype;
      else if (c->topic == topic && c->datatype != type)
        fail(topic + ": holds both " + type + " and " + c->datatype + " messages; a colour or depth topic must carry "
             "one message type (choose another topic with --rgb-topic / --depth-topic)");
    return type;
  };
  const auto choose = [&](const std::string& given, const std::vector<std::string>& known, bool depth,
                          const std::string& what, const std::string& flag) {
    if (!given.empty()) {
      if (typeOf(given).empty())
        fail("no sensor_msgs/Image or CompressedImage messages on " + flag + " " + given + "; topics:" + listing);
      return given;
    }
    for (const auto& k : known)
      if (!typeOf(k).empty()) return k;
    std::vector<std::string> candidates;
    for (const auto* c : images)
      if ((lower(c->topic).find("depth") != std::string::npos) == depth &&
          std::find(candidates.begin(), candidates.end(), c->topic) == candidates.end())
        candidates.push_back(c->topic);
    if (candidates.size() == 1) return candidates[0];
    if (images.empty()) fail("no image topics (sensor_msgs/Image or CompressedImage); topics:" + listing);
    fail(candidates.empty() ? "no " + what + " image topic found; give it with " + flag + "; topics:" + listing
                            : std::to_string(candidates.size()) + " candidate " + what + " topics; choose one with " +
                                  flag + "; topics:" + listing);
  };
  color_topic = choose(options.rgb_topic, kColorTopics, false, "colour", "--rgb-topic");
  depth_topic = choose(options.depth_topic, kDepthTopics, true, "depth", "--depth-topic");
  if (color_topic == depth_topic) fail("colour and depth topics are the same (" + color_topic + ")");
  color_type = typeOf(color_topic);
  depth_type = typeOf(depth_topic);
}

// Each image message's header stamp, its encoding checked: one pass over both topics in the bag's
// order (a compressed chunk holding a colour and a depth message is decompressed once).
void BagReader::Impl::readStamps() {
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{color_topic, depth_topic}));
  for (const rosbag::MessageInstance& m : view) {
    const bool is_color = m.getTopic() == color_topic;
    const std::string& topic = is_color ? color_topic : depth_topic;
    const std::string& type = is_color ? color_type : depth_type;
    std::vector<double>& out = is_color ? color_stamps : depth_stamps;
    double t;
    std::string encoding;
    try {
      if (type == kImageType) {
        const auto msg = instantiate<ImageMsg>(m, path + ":" + topic);
        t = seconds(msg->header.stamp);
        encoding = str(msg->encoding);
      } else {
        const auto msg = instantiate<CompressedMsg>(m, path + ":" + topic);
        t = seconds(msg->header.stamp);
        encoding = str(msg->format);
      }
    } catch (const ros::Exception& e) {
      fail(topic + " message " + std::to_string(out.size()) + " does not decode as the topic's " + type + " (" +
           e.what() + "): the topic mixes sensor_msgs/Image and CompressedImage messages, or the bag is corrupt");
    }
    if (const std::string problem = encodingProblem(type, encoding, is_color ? Kind::kColor : Kind::kDepth);
        !problem.empty())
      fail(topic + " message " + std::to_string(out.size()) + ": " + problem);
    if (!out.empty() && !(t > out.back()))
      fail(topic + " message " + std::to_string(out.size()) + ": header stamp " + timestampName(t) +
           " is not after the previous message's " + timestampName(out.back()) +
           " (stamps must increase in the bag's order)");
    out.push_back(t);
  }
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
  const std::string sibling = color_topic.substr(0, color_topic.rfind('/') + 1) + "camera_info";
  std::vector<std::string> infos;
  rosbag::View all(bag);
  for (const rosbag::ConnectionInfo* c : all.getConnections())
    if (c->datatype == kCameraInfoType && std::find(infos.begin(), infos.end(), c->topic) == infos.end())
      infos.push_back(c->topic);
  std::string topic;
  if (std::find(infos.begin(), infos.end(), sibling) != infos.end()) topic = sibling;
  else if (infos.size() == 1) topic = infos[0];
  else
    fail("no camera intrinsics: no sensor_msgs/CameraInfo on " + sibling +
         (infos.empty() ? std::string() : " (and " + std::to_string(infos.size()) + " other CameraInfo topics)") +
         "; give --camera fr1|fr2|fr3|fx,fy,cx,cy,width,height");
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  if (view.size() == 0) fail(topic + ": no CameraInfo message; give --camera");
  const auto msg = instantiate<CameraInfoMsg>(*view.begin(), path + ":" + topic);
  std::vector<double> v = {msg->K[0], msg->K[4], msg->K[2], msg->K[5], double(msg->width), double(msg->height)};
  const std::string model = str(msg->distortion_model);
  bool distorted = false;
  for (double d : msg->D) distorted = distorted || d != 0;
  if (distorted) {
    if (model != "plumb_bob" && !(model == "rational_polynomial" && msg->D.size() >= 8 && msg->D[5] == 0 &&
                                  msg->D[6] == 0 && msg->D[7] == 0))
      fail(topic + ": distortion model '" + model + "' is not supported (plumb_bob); give --camera or --no-undistort");
    for (size_t k = 0; k < 5; ++k) v.push_back(k < msg->D.size() ? msg->D[k] : 0.0);
  }
  if (const auto problem = cameraValuesProblem(v)) fail(topic + ": " + *problem + "; give --camera");
  camera = cameraModelFromValues(v);
}

void BagReader::Impl::checkSize(const cv::Mat& image, const std::string& name) const {
  const CameraIntrinsics& c = camera.intrinsics;
  if (image.cols != c.width || image.rows != c.height)
    throw InputError(name + ": image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     ", the camera is " + std::to_string(c.width) + "x" + std::to_string(c.height));
}

namespace {

// The pixels of a raw image message (rows `step` bytes apart), copied; InputError when the
// message holds fewer bytes than it declares.
cv::Mat wrapImage(const ImageMsg& m, int type, const std::string& name) {
  const size_t row = size_t(m.width) * CV_ELEM_SIZE(type);
  if (m.width == 0 || m.height == 0 || m.step < row || m.data.size() < size_t(m.step) * m.height ||
      static_cast<long long>(m.width) * m.height > kMaxImagePixels)
    throw InputError(name + ": image message of " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                     " (step " + std::to_string(m.step) + ") holds " + std::to_string(m.data.size()) + " bytes");
  cv::Mat view(int(m.height), int(m.width), type, const_cast<uint8_t*>(m.data.data()), m.step);
  cv::Mat out = view.clone();
  if (m.is_bigendian && CV_ELEM_SIZE1(type) > 1) {
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

}  // namespace

cv::Mat BagReader::Impl::decodeColor(const rosbag::MessageInstance& m, const std::string& name) const {
  cv::Mat bgr;
  if (color_type == kImageType) {
    const auto msg = instantiate<ImageMsg>(m, name);
    const std::string e = lower(str(msg->encoding));
    if (e == "rgb8") cv::cvtColor(wrapImage(*msg, CV_8UC3, name), bgr, cv::COLOR_RGB2BGR);
    else if (e == "bgr8") bgr = wrapImage(*msg, CV_8UC3, name);
    else if (e == "mono8") cv::cvtColor(wrapImage(*msg, CV_8UC1, name), bgr, cv::COLOR_GRAY2BGR);
    else if (e == "rgba8") cv::cvtColor(wrapImage(*msg, CV_8UC4, name), bgr, cv::COLOR_RGBA2BGR);
    else if (e == "bgra8") cv::cvtColor(wrapImage(*msg, CV_8UC4, name), bgr, cv::COLOR_BGRA2BGR);
    else throw InputError(name + ": " + encodingProblem(color_type, e, Kind::kColor));
  } else {
    const auto msg = instantiate<CompressedMsg>(m, name);
    const cv::Mat bytes(1, int(msg->data.size()), CV_8U, const_cast<uint8_t*>(msg->data.data()));
    // A PNG declares its size before any pixel is decoded (image_file.h): refuse a wrong one there.
    if (msg->data.size() >= 24 && msg->data[1] == 'P' && msg->data[2] == 'N' && msg->data[3] == 'G') {
      const auto be32 = [&](size_t at) {
        return uint32_t(msg->data[at]) << 24 | uint32_t(msg->data[at + 1]) << 16 | uint32_t(msg->data[at + 2]) << 8 |
               uint32_t(msg->data[at + 3]);
      };
      const CameraIntrinsics& c = camera.intrinsics;
      if (be32(16) != uint32_t(c.width) || be32(20) != uint32_t(c.height))
        throw InputError(name + ": image is " + std::to_string(be32(16)) + "x" + std::to_string(be32(20)) +
                         ", the camera is " + std::to_string(c.width) + "x" + std::to_string(c.height));
    }
    cv::Mat decoded;
    try {
      decoded = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
    }
    if (decoded.empty()) throw InputError(name + ": compressed image (" + str(msg->format) + ") does not decode");
    bgr = toBgr(decoded, name);
  }
  checkSize(bgr, name);
  return bgr;
}

cv::Mat BagReader::Impl::decodeDepth(const rosbag::MessageInstance& m, const std::string& name, double& scale) const {
  const auto msg = instantiate<ImageMsg>(m, name);
  const std::string e = lower(str(msg->encoding));
  cv::Mat depth;
  if (e == "16uc1" || e == "mono16") {
    depth = wrapImage(*msg, CV_16UC1, name);
    scale = options.bag_depth_scale;
  } else if (e == "32fc1") {
    depth = wrapImage(*msg, CV_32FC1, name);
    // No measurement is 0 in every stage; ROS drivers write NaN (and some +-inf or negatives).
    depth.forEach<float>([](float& d, const int*) {
      if (!std::isfinite(d) || d < 0) d = 0;
    });
    scale = 1;
  } else {
    throw InputError(name + ": " + encodingProblem(depth_type, e, Kind::kDepth));
  }
  checkSize(depth, name);
  return depth;
}

BagReader::BagReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BagReader::BagReader(BagReader&&) noexcept = default;
BagReader& BagReader::operator=(BagReader&&) noexcept = default;
BagReader::~BagReader() = default;

BagReader BagReader::open(const std::string& path, const SequenceOptions& options) {
  requireBagFile(path);
  checkDepthScale(options.bag_depth_scale, "--depth-scale");
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  try {
    impl->bag.open(path, rosbag::bagmode::Read);
    impl->pickTopics();
    impl->readStamps();
    impl->readCamera();
  } catch (const ros::Exception& e) {  // rosbag's BagException, a message's StreamOverrunException
    throw InputError(path + ": not a readable ROS 1 bag (truncated or corrupt?): " + e.what());
  }
  const std::vector<double>& tc = impl->color_stamps;
  const std::vector<double>& td = impl->depth_stamps;
  impl->pairs = associate(tc, td, options.max_time_diff, StampLimit::kInclusive);
  if (impl->pairs.empty())
    impl->fail("no colour message on " + impl->color_topic + " has a depth message on " + impl->depth_topic +
               " within " + std::to_string(options.max_time_diff) + " s (" + std::to_string(tc.size()) + " colour, " +
               std::to_string(td.size()) + " depth messages; check their header stamps)");
  impl->color_cursor = std::make_unique<TopicCursor>(impl->bag, impl->color_topic);
  impl->depth_cursor = std::make_unique<TopicCursor>(impl->bag, impl->depth_topic);
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
  try {
    f.bgr8 = d.decodeColor(d.color_cursor->at(ci), f.name);
    f.depth = d.decodeDepth(d.depth_cursor->at(di), depth_name, f.depth_scale);
  } catch (const ros::Exception& e) {
    d.fail(std::string("reading message failed (truncated or corrupt bag?): ") + e.what());
  }
  return f;
}

}  // namespace ff

#else  // FLOWFUSION_HAVE_ROSBAG

namespace ff {

bool bagSupportBuilt() { return false; }

struct BagReader::Impl {};

// No BagReader exists in this build (open() throws), so none of these is reached.
[[noreturn]] static void noBagSupport() { throw std::logic_error("flowfusion was built without ROS bag support"); }
BagReader::BagReader(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
BagReader::BagReader(BagReader&&) noexcept = default;
BagReader& BagReader::operator=(BagReader&&) noexcept = default;
BagReader::~BagReader() = default;
size_t BagReader::size() const { noBagSupport(); }
BagFrame BagReader::read(size_t) { noBagSupport(); }
const CameraModel& BagReader::camera() const { noBagSupport(); }
const std::string& BagReader::path() const { noBagSupport(); }
const std::string& BagReader::colorTopic() const { noBagSupport(); }
const std::string& BagReader::depthTopic() const { noBagSupport(); }

BagReader BagReader::open(const std::string& path, const SequenceOptions&) {
  throw InputError(path + ": this flowfusion was built without ROS bag support; install Debian's "
                          "librosbag-storage-dev and libsensor-msgs-dev (bash scripts/install-deps.sh), configure "
                          "and build again, or convert the bag to a TUM folder elsewhere");
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROSBAG

// ROS 1 bags (format 2.0, uncompressed, bz2 or lz4 chunks) as a RosRecording, through Debian's
// librosbag-storage-dev: the container and the messages are rosbag's and sensor_msgs'.
#include <filesystem>

#include "flowfusion/core/error.h"
#include "flowfusion/io/ros_recording.h"

#ifdef FLOWFUSION_HAVE_ROSBAG

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include "flowfusion/io/ros_messages.h"

namespace ff {

namespace {

using ros1::CameraInfoMsg;
using ros1::ImageMsg;
using CompressedMsg = ros1::CompressedImageMsg;

constexpr const char* kImageType = "sensor_msgs/Image";
constexpr const char* kCompressedType = "sensor_msgs/CompressedImage";
constexpr const char* kCameraInfoType = "sensor_msgs/CameraInfo";

template <class S>
std::string str(const S& s) {
  return std::string(s.begin(), s.end());
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

RosImage imageOf(const rosbag::MessageInstance& m, const std::string& type, const std::string& where) {
  RosImage out;
  if (type == kImageType) {
    auto msg = instantiate<ImageMsg>(m, where);
    out.stamp = {msg->header.stamp.sec, msg->header.stamp.nsec};
    out.encoding = str(msg->encoding);
    out.width = msg->width;
    out.height = msg->height;
    out.step = msg->step;
    out.big_endian = msg->is_bigendian != 0;
    out.data = msg->data.data();
    out.size = msg->data.size();
    out.keep = std::shared_ptr<const void>(msg.get(), [msg](const void*) {});
  } else {
    auto msg = instantiate<CompressedMsg>(m, where);
    out.stamp = {msg->header.stamp.sec, msg->header.stamp.nsec};
    out.compressed = true;
    out.encoding = str(msg->format);
    out.data = msg->data.data();
    out.size = msg->data.size();
    out.keep = std::shared_ptr<const void>(msg.get(), [msg](const void*) {});
  }
  return out;
}

RosType typeOf(const std::string& datatype) {
  if (datatype == kImageType) return RosType::kImage;
  if (datatype == kCompressedType) return RosType::kCompressedImage;
  if (datatype == kCameraInfoType) return RosType::kCameraInfo;
  return RosType::kOther;
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

class Ros1Recording : public RosRecording {
 public:
  explicit Ros1Recording(const std::string& path) : path_(path) {
    guarded([&] { bag_.open(path, rosbag::bagmode::Read); });
  }

  std::vector<RosTopic> topics() override {
    std::vector<RosTopic> out;
    guarded([&] {
      rosbag::View all(bag_);
      for (const rosbag::ConnectionInfo* c : all.getConnections())
        out.push_back({c->topic, c->datatype, typeOf(c->datatype)});
    });
    return out;
  }

  void scanImages(const std::vector<std::string>& topics,
                  const std::function<void(size_t, const RosImage&)>& visit) override {
    topics_ = topics;
    types_.assign(topics.size(), "");
    cursors_.clear();
    for (const RosTopic& t : this->topics())
      for (size_t k = 0; k < topics.size(); ++k)
        if (t.name == topics[k] && types_[k].empty()) types_[k] = t.datatype;
    std::vector<size_t> counts(topics.size(), 0);
    guarded([&] {
      rosbag::View view(bag_, rosbag::TopicQuery(topics));
      for (const rosbag::MessageInstance& m : view) {
        const size_t slot = size_t(std::find(topics.begin(), topics.end(), m.getTopic()) - topics.begin());
        RosImage image;
        try {
          image = imageOf(m, types_[slot], path_ + ":" + topics[slot]);
        } catch (const ros::Exception& e) {
          throw InputError(path_ + ": " + topics[slot] + " message " + std::to_string(counts[slot]) +
                           " does not decode as the topic's " + types_[slot] + " (" + e.what() +
                           "): the topic mixes sensor_msgs/Image and CompressedImage messages, or the bag is corrupt");
        }
        visit(slot, image);
        ++counts[slot];
      }
    });
    for (const std::string& t : topics) cursors_.push_back(std::make_unique<TopicCursor>(bag_, t));
  }

  RosImage image(size_t slot, size_t index) override {
    const std::string name = path_ + ":" + topics_.at(slot) + "#" + std::to_string(index);
    try {
      return imageOf(cursors_.at(slot)->at(index), types_[slot], name);
    } catch (const ros::Exception& e) {
      throw InputError(path_ + ": reading message failed (truncated or corrupt bag?): " + e.what());
    }
  }

  std::optional<RosCameraInfo> firstCameraInfo(const std::string& topic) override {
    std::optional<RosCameraInfo> out;
    guarded([&] {
      rosbag::View view(bag_, rosbag::TopicQuery(topic));
      if (view.size() == 0) return;
      const auto msg = instantiate<CameraInfoMsg>(*view.begin(), path_ + ":" + topic);
      RosCameraInfo info;
      info.width = msg->width;
      info.height = msg->height;
      info.distortion_model = str(msg->distortion_model);
      info.d.assign(msg->D.begin(), msg->D.end());
      std::copy(msg->K.begin(), msg->K.end(), info.k.begin());
      out = info;
    });
    return out;
  }

 private:
  // Runs f, a rosbag BagException or a message's StreamOverrunException becoming an InputError.
  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const ros::Exception& e) {
      throw InputError(path_ + ": not a readable ROS 1 bag (truncated or corrupt?): " + e.what());
    }
  }

  std::string path_;
  rosbag::Bag bag_;
  std::vector<std::string> topics_, types_;
  std::vector<std::unique_ptr<TopicCursor>> cursors_;
};

}  // namespace

bool bagSupportBuilt() { return true; }

std::unique_ptr<RosRecording> openRos1Recording(const std::string& path) {
  requireBagFile(path);
  return std::make_unique<Ros1Recording>(path);
}

}  // namespace ff

#else  // FLOWFUSION_HAVE_ROSBAG

namespace ff {

bool bagSupportBuilt() { return false; }

std::unique_ptr<RosRecording> openRos1Recording(const std::string& path) {
  throw InputError(path + ": this flowfusion was built without ROS bag support; install Debian's "
                          "librosbag-storage-dev and libsensor-msgs-dev (bash scripts/install-deps.sh), configure "
                          "and build again, or convert the bag to a TUM folder elsewhere");
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROSBAG

// ROS 2 bags as a RosRecording: a rosbag2 folder (metadata.yaml naming its .mcap or .db3 files,
// read one after another) or one .mcap or .db3 file, their messages CDR (io/cdr.h). The schemas an
// MCAP file declares are checked against the sensor_msgs fields the decoders read.
#include <filesystem>
#include <fstream>
#include <sstream>

#include "flowfusion/core/error.h"
#include "flowfusion/io/ros_recording.h"

#ifdef FLOWFUSION_HAVE_ROS2BAG

#include <algorithm>
#include <map>

#include "flowfusion/io/cdr.h"
#include "flowfusion/io/db3_reader.h"
#include "flowfusion/io/mcap_reader.h"

namespace fs = std::filesystem;

namespace ff {

namespace {

struct Ros2Topic {
  std::string name, type, encoding;        // type e.g. sensor_msgs/msg/Image; encoding e.g. cdr
  std::string schema_encoding, schema;     // an MCAP channel's schema ("" in .db3 files)
};

// Where a message is in its file: MCAP (chunk, offset) or a .db3 row id (in a).
struct Location {
  uint64_t a = 0, b = 0;
};

struct Bytes {
  const uint8_t* data = nullptr;
  size_t size = 0;
  std::shared_ptr<const void> keep;
};

// One storage file of a ROS 2 bag.
class Storage {
 public:
  virtual ~Storage() = default;
  virtual std::vector<Ros2Topic> topics() = 0;
  // The messages on `topics` in the file's order: visit(slot, bytes, where) returns false to stop.
  virtual void scan(const std::vector<std::string>& topics,
                    const std::function<bool(size_t, const Bytes&, const Location&)>& visit) = 0;
  virtual Bytes message(const Location& where) = 0;
};

class McapStorage : public Storage {
 public:
  explicit McapStorage(const std::string& path) : mcap_(path) {}
  std::vector<Ros2Topic> topics() override {
    std::vector<Ros2Topic> out;
    for (const auto& [id, c] : mcap_.channels())
      out.push_back({c.topic, c.schema_name, c.message_encoding, c.schema_encoding, c.schema_data});
    return out;
  }
  void scan(const std::vector<std::string>& topics,
            const std::function<bool(size_t, const Bytes&, const Location&)>& visit) override {
    std::map<uint16_t, size_t> slots;
    for (const auto& [id, c] : mcap_.channels())
      if (const auto it = std::find(topics.begin(), topics.end(), c.topic); it != topics.end())
        slots[id] = size_t(it - topics.begin());
    std::set<uint16_t> ids;
    for (const auto& [id, slot] : slots) ids.insert(id);
    if (ids.empty()) return;
    mcap_.scan(ids, [&](const McapMessage& m, const McapLocation& where) {
      return visit(slots[m.channel], {m.data, m.size, m.keep}, {where.chunk, where.offset});
    });
  }
  Bytes message(const Location& where) override {
    const McapMessage m = mcap_.message({where.a, where.b});
    return {m.data, m.size, m.keep};
  }

 private:
  McapReader mcap_;
};

class Db3Storage : public Storage {
 public:
  explicit Db3Storage(const std::string& path) : db_(path) {}
  std::vector<Ros2Topic> topics() override {
    std::vector<Ros2Topic> out;
    for (const Db3Reader::Topic& t : db_.topics()) out.push_back({t.name, t.type, t.serialization_format, "", ""});
    return out;
  }
  void scan(const std::vector<std::string>& topics,
            const std::function<bool(size_t, const Bytes&, const Location&)>& visit) override {
    std::map<int64_t, size_t> slots;
    for (const Db3Reader::Topic& t : db_.topics())
      if (const auto it = std::find(topics.begin(), topics.end(), t.name); it != topics.end())
        slots[t.id] = size_t(it - topics.begin());
    std::set<int64_t> ids;
    for (const auto& [id, slot] : slots) ids.insert(id);
    if (ids.empty()) return;
    db_.scan(ids, [&](int64_t topic, const uint8_t* data, size_t size, int64_t row) {
      return visit(slots[topic], {data, size, nullptr}, {uint64_t(row), 0});
    });
  }
  Bytes message(const Location& where) override {
    auto data = std::make_shared<std::vector<uint8_t>>(db_.message(int64_t(where.a)));
    return {data->data(), data->size(), data};
  }

 private:
  Db3Reader db_;
};

RosType typeOf(const std::string& type) {
  if (type == "sensor_msgs/msg/Image") return RosType::kImage;
  if (type == "sensor_msgs/msg/CompressedImage") return RosType::kCompressedImage;
  if (type == "sensor_msgs/msg/CameraInfo") return RosType::kCameraInfo;
  return RosType::kOther;
}

// The leading fields ("type name", std_msgs/msg/X spelt std_msgs/X) the decoders read of each type.
std::vector<std::string> fieldsRead(RosType type) {
  switch (type) {
    case RosType::kImage:
      return {"std_msgs/Header header", "uint32 height", "uint32 width", "string encoding", "uint8 is_bigendian",
              "uint32 step", "uint8[] data"};
    case RosType::kCompressedImage: return {"std_msgs/Header header", "string format", "uint8[] data"};
    case RosType::kCameraInfo:
      return {"std_msgs/Header header", "uint32 height", "uint32 width", "string distortion_model", "float64[] d",
              "float64[9] k"};
    case RosType::kOther: break;
  }
  return {};
}

// The top-level fields of a ros2msg definition, constants and comments left out.
std::vector<std::string> declaredFields(const std::string& schema) {
  std::vector<std::string> out;
  std::istringstream in(schema);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("===", 0) == 0) break;
    line = line.substr(0, line.find('#'));
    std::istringstream words(line);
    std::string type, name;
    if (!(words >> type >> name) || name.find('=') != std::string::npos) continue;
    std::string more;
    if (words >> more && more[0] == '=') continue;
    if (const auto at = type.find("/msg/"); at != std::string::npos) type.erase(at, 4);
    if (type == "Header") type = "std_msgs/Header";
    out.push_back(type + " " + name);
  }
  return out;
}

// Why the topic's messages cannot be read as its type, or "".
std::string topicProblem(const Ros2Topic& t) {
  if (t.encoding != "cdr") return "messages are encoded as '" + t.encoding + "', not cdr";
  if (t.schema.empty() || t.schema_encoding != "ros2msg") return "";
  const std::vector<std::string> want = fieldsRead(typeOf(t.type)), have = declaredFields(t.schema);
  if (have.size() >= want.size() && std::equal(want.begin(), want.end(), have.begin())) return "";
  std::string listed;
  for (const auto& f : have) listed += (listed.empty() ? "" : ", ") + f;
  return "schema " + t.type + " declares fields (" + listed + ") that are not sensor_msgs' (" + want.front() + ", ...)";
}

// A rosbag2 folder's storage files in order, from metadata.yaml's relative_file_paths.
std::vector<std::string> folderFiles(const fs::path& dir) {
  const fs::path meta = dir / "metadata.yaml";
  std::ifstream in(meta);
  if (!in) throw InputError(meta.string() + ": cannot read it");
  std::vector<std::string> files;
  bool in_list = false;
  for (std::string line; std::getline(in, line);) {
    const size_t first = line.find_first_not_of(' ');
    if (first == std::string::npos) continue;
    const std::string item = line.substr(first);
    if (item.rfind("compression_format:", 0) == 0) {
      std::string value = item.substr(19);
      value.erase(std::remove_if(value.begin(), value.end(), [](char c) { return c == ' ' || c == '"' || c == '\''; }),
                  value.end());
      if (!value.empty())
        throw InputError(meta.string() + ": compressed rosbag2 files (compression_format: " + value +
                         ") are not read; record without --compression-mode (MCAP chunks may be zstd or lz4)");
    }
    if (item.rfind("relative_file_paths:", 0) == 0) {
      in_list = true;
      continue;
    }
    if (in_list && item.rfind("- ", 0) == 0) files.push_back((dir / item.substr(2)).string());
    else if (in_list) in_list = false;
  }
  if (files.empty()) throw InputError(meta.string() + ": lists no relative_file_paths");
  return files;
}

class Ros2Recording : public RosRecording {
 public:
  explicit Ros2Recording(std::string path) : path_(std::move(path)) {
    std::error_code ec;
    const bool folder = fs::is_directory(path_, ec);
    if (!folder && !fs::exists(path_, ec)) throw InputError(path_ + ": ROS 2 bag does not exist");
    if (!folder && !fs::is_regular_file(path_, ec))
      throw InputError(path_ + ": is not a regular file (a FIFO, socket or device); a ROS 2 bag is read from disk");
    for (const std::string& file : folder ? folderFiles(path_) : std::vector<std::string>{path_}) {
      const std::string ext = fs::path(file).extension().string();
      if (ext == ".mcap") files_.push_back(std::make_unique<McapStorage>(file));
      else if (ext == ".db3") files_.push_back(std::make_unique<Db3Storage>(file));
      else throw InputError(file + ": a rosbag2 storage file must be .mcap or .db3");
      names_.push_back(file);
    }
  }

  std::vector<RosTopic> topics() override {
    std::vector<RosTopic> out;
    for (const Ros2Topic& t : allTopics())
      if (std::none_of(out.begin(), out.end(), [&](const RosTopic& o) { return o.name == t.name && o.datatype == t.type; }))
        out.push_back({t.name, t.type, typeOf(t.type)});
    return out;
  }

  void scanImages(const std::vector<std::string>& topics,
                  const std::function<void(size_t, const RosImage&)>& visit) override {
    topics_ = topics;
    where_.assign(topics.size(), {});
    std::vector<RosType> types(topics.size(), RosType::kOther);
    for (const Ros2Topic& t : allTopics())
      for (size_t k = 0; k < topics.size(); ++k)
        if (t.name == topics[k]) {
          checkTopic(t);
          types[k] = typeOf(t.type);
        }
    types_ = types;
    for (size_t f = 0; f < files_.size(); ++f) {
      bool in_visit = false;  // an error of the caller's passes as it is
      try {
        files_[f]->scan(topics, [&](size_t slot, const Bytes& b, const Location& at) {
          const RosImage m = decode(slot, b, where_[slot].size(), f);
          in_visit = true;
          visit(slot, m);
          in_visit = false;
          where_[slot].emplace_back(f, at);
          return true;
        });
      } catch (const InputError& e) {
        if (in_visit) throw;
        std::string listed;
        for (const std::string& t : topics) listed += (listed.empty() ? "" : ", ") + t;
        throw InputError(std::string(e.what()) + " (reading " + listed + ")");
      }
    }
  }

  RosImage image(size_t slot, size_t index) override {
    const auto& [f, at] = where_.at(slot).at(index);
    return decode(slot, files_[f]->message(at), index, f);
  }

  std::optional<RosCameraInfo> firstCameraInfo(const std::string& topic) override {
    for (const Ros2Topic& t : allTopics())
      if (t.name == topic) checkTopic(t);
    std::optional<RosCameraInfo> out;
    for (size_t f = 0; f < files_.size() && !out; ++f)
      files_[f]->scan({topic}, [&](size_t, const Bytes& b, const Location&) {
        try {
          out = decodeRos2CameraInfo(b.data, b.size);
        } catch (const CdrError& e) {
          throw InputError(names_[f] + ": " + topic + " message 0 does not decode as sensor_msgs/msg/CameraInfo: " +
                           e.what());
        }
        return false;
      });
    return out;
  }

 private:
  std::vector<Ros2Topic> allTopics() {
    std::vector<Ros2Topic> out;
    for (const auto& f : files_)
      for (Ros2Topic& t : f->topics()) out.push_back(std::move(t));
    return out;
  }

  void checkTopic(const Ros2Topic& t) const {
    if (const std::string problem = topicProblem(t); !problem.empty()) throw InputError(path_ + ": " + t.name + ": " + problem);
  }

  RosImage decode(size_t slot, const Bytes& b, size_t index, size_t file) const {
    RosImage m;
    try {
      m = types_[slot] == RosType::kCompressedImage ? decodeRos2CompressedImage(b.data, b.size)
                                                    : decodeRos2Image(b.data, b.size);
    } catch (const CdrError& e) {
      throw InputError(names_[file] + ": " + topics_[slot] + " message " + std::to_string(index) +
                       " does not decode as " +
                       (types_[slot] == RosType::kCompressedImage ? "sensor_msgs/msg/CompressedImage"
                                                                  : "sensor_msgs/msg/Image") +
                       " (" + e.what() + ")");
    }
    m.keep = b.keep;
    return m;
  }

  std::string path_;
  std::vector<std::unique_ptr<Storage>> files_;
  std::vector<std::string> names_;
  std::vector<std::string> topics_;
  std::vector<RosType> types_;
  std::vector<std::vector<std::pair<size_t, Location>>> where_;  // per slot: (file, location) of each message
};

}  // namespace

bool ros2BagSupportBuilt() { return true; }

std::unique_ptr<RosRecording> openRos2Recording(const std::string& path) { return std::make_unique<Ros2Recording>(path); }

}  // namespace ff

#else  // FLOWFUSION_HAVE_ROS2BAG

namespace ff {

bool ros2BagSupportBuilt() { return false; }

std::unique_ptr<RosRecording> openRos2Recording(const std::string& path) {
  throw InputError(path + ": this flowfusion was built without ROS 2 bag support; install Debian's libzstd-dev, "
                          "liblz4-dev and libsqlite3-dev (bash scripts/install-deps.sh), configure and build again");
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROS2BAG

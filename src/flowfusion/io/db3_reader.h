#pragma once
// rosbag2's sqlite storage (.db3, the default before MCAP): the tables topics(id, name, type,
// serialization_format) and messages(id, topic_id, timestamp, data), read with libsqlite3.
// Messages are read one row at a time in the recording's (timestamp) order, and again by row id.
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <vector>

struct sqlite3;

namespace ff {

class Db3Reader {
 public:
  struct Topic {
    int64_t id = 0;
    std::string name, type, serialization_format;  // e.g. /camera/rgb/image_color, sensor_msgs/msg/Image, cdr
  };

  // Opens the file read-only and reads its topics; InputError naming the file when it is not a
  // sqlite database or lacks rosbag2's tables and columns.
  explicit Db3Reader(std::string path);
  ~Db3Reader();
  Db3Reader(const Db3Reader&) = delete;
  Db3Reader& operator=(const Db3Reader&) = delete;

  const std::vector<Topic>& topics() const { return topics_; }
  // The messages of `topic_ids` by timestamp: visit(topic id, bytes, size, row id) returns false to stop.
  void scan(const std::set<int64_t>& topic_ids,
            const std::function<bool(int64_t, const uint8_t*, size_t, int64_t)>& visit);
  // The data of message row `id`.
  std::vector<uint8_t> message(int64_t id);
  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& what) const;
  std::string path_;
  sqlite3* db_ = nullptr;
  std::vector<Topic> topics_;
};

}  // namespace ff

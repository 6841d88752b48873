#include "flowfusion/io/db3_reader.h"

// Built with the ROS 2 bag readers only (cmake/FlowfusionRos2Bag.cmake).
#ifdef FLOWFUSION_HAVE_ROS2BAG

#include <sqlite3.h>

#include <filesystem>
#include <memory>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

using Statement = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

std::string text(sqlite3_stmt* s, int column) {
  const unsigned char* t = sqlite3_column_text(s, column);
  return t ? reinterpret_cast<const char*>(t) : "";
}

}  // namespace

void Db3Reader::fail(const std::string& what) const {
  throw InputError(path_ + ": " + what + (db_ ? std::string(" (sqlite: ") + sqlite3_errmsg(db_) + ")" : ""));
}

Db3Reader::Db3Reader(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_, ec)) throw InputError(path_ + ": no such rosbag2 .db3 file");
  if (sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) fail("cannot open it as sqlite");
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db_, "SELECT id, name, type, serialization_format FROM topics", -1, &raw, nullptr) != SQLITE_OK)
    fail("not a rosbag2 sqlite file: no table topics(id, name, type, serialization_format)");
  const Statement s(raw, sqlite3_finalize);
  int rc;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW)
    topics_.push_back({sqlite3_column_int64(s.get(), 0), text(s.get(), 1), text(s.get(), 2), text(s.get(), 3)});
  if (rc != SQLITE_DONE) fail("reading its topics failed (truncated or corrupt?)");
  sqlite3_stmt* probe = nullptr;
  if (sqlite3_prepare_v2(db_, "SELECT id, topic_id, timestamp, data FROM messages LIMIT 0", -1, &probe, nullptr) != SQLITE_OK)
    fail("not a rosbag2 sqlite file: no table messages(id, topic_id, timestamp, data)");
  sqlite3_finalize(probe);
}

Db3Reader::~Db3Reader() { sqlite3_close(db_); }

void Db3Reader::scan(const std::set<int64_t>& topic_ids,
                     const std::function<bool(int64_t, const uint8_t*, size_t, int64_t)>& visit) {
  std::string list;
  for (int64_t id : topic_ids) {
    if (!list.empty()) list += ',';
    list += std::to_string(id);
  }
  const std::string sql =
      "SELECT id, topic_id, data FROM messages WHERE topic_id IN (" + list + ") ORDER BY timestamp, id";
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &raw, nullptr) != SQLITE_OK) fail("cannot query its messages");
  const Statement s(raw, sqlite3_finalize);
  int rc;
  while ((rc = sqlite3_step(s.get())) == SQLITE_ROW) {
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(s.get(), 2));
    const auto size = static_cast<size_t>(sqlite3_column_bytes(s.get(), 2));
    if (!visit(sqlite3_column_int64(s.get(), 1), data, size, sqlite3_column_int64(s.get(), 0))) return;
  }
  if (rc != SQLITE_DONE) fail("reading its messages failed (truncated or corrupt?)");
}

std::vector<uint8_t> Db3Reader::message(int64_t id) {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db_, "SELECT data FROM messages WHERE id = ?", -1, &raw, nullptr) != SQLITE_OK)
    fail("cannot query its messages");
  const Statement s(raw, sqlite3_finalize);
  sqlite3_bind_int64(s.get(), 1, id);
  if (sqlite3_step(s.get()) != SQLITE_ROW) fail("message row " + std::to_string(id) + " cannot be read (corrupt?)");
  const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(s.get(), 0));
  return std::vector<uint8_t>(data, data + sqlite3_column_bytes(s.get(), 0));
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROS2BAG

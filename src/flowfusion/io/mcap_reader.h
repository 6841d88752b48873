#pragma once
// MCAP files (format version 0, the container `ros2 bag record` writes by default): the record
// layout, chunks stored uncompressed, zstd or lz4, and the summary section with its chunk
// indexes when the file has one, so that chunks holding none of the wanted channels are skipped
// without being read. A file without a summary (a recording cut short by a crash) is read by a
// linear scan up to its last whole record. Chunk, summary and data-section CRCs are checked where
// the writer wrote them (non-zero). Memory holds one or two decompressed chunks, not the file.
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace ff {

struct McapChannel {
  uint16_t id = 0, schema_id = 0;       // schema_id 0: no schema
  std::string topic, message_encoding;                    // e.g. "cdr"
  std::string schema_name, schema_encoding, schema_data;  // e.g. sensor_msgs/msg/Image, ros2msg, its text
};

// Where a message record is: inside the chunk record at `chunk` (its file offset) at `offset` of
// the decompressed records, or (chunk == kNoChunk) at file offset `offset`.
struct McapLocation {
  static constexpr uint64_t kNoChunk = ~uint64_t(0);
  uint64_t chunk = kNoChunk;
  uint64_t offset = 0;
};

// A message's bytes, valid while `keep` is held.
struct McapMessage {
  uint16_t channel = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
  std::shared_ptr<const void> keep;
};

class McapReader {
 public:
  // Reads the magic, the summary (or scans the file for channels); throws InputError naming the
  // file on a missing or unknown-version magic, a bad CRC, or a record that does not parse.
  explicit McapReader(std::string path);
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  const std::map<uint16_t, McapChannel>& channels() const { return channels_; }
  // The messages on `channels` in the file's order: visit(message, where) returns false to stop.
  void scan(const std::set<uint16_t>& channels,
            const std::function<bool(const McapMessage&, const McapLocation&)>& visit);
  McapMessage message(const McapLocation& where);
  // Whether the summary's chunk indexes were used (else: a linear scan).
  bool indexed() const { return indexed_; }
  // Whether the linear scan stopped at a record cut short (the file is truncated).
  bool truncated() const { return truncated_; }
  const std::string& path() const { return path_; }

 private:
  // A chunk record, or a message record outside chunks (loose), in the file.
  struct ChunkRef {
    uint64_t offset = 0, length = 0;  // bytes, the whole record
    std::set<uint16_t> channels;      // its channels by its message indexes; empty: unknown
    bool loose = false;
  };
  using Buffer = std::shared_ptr<std::vector<uint8_t>>;

  [[noreturn]] void fail(const std::string& message) const;
  void read(uint64_t offset, size_t n, uint8_t* out) const;
  std::vector<uint8_t> read(uint64_t offset, size_t n) const;
  void readStart();
  bool readSummary();
  void scanLinear();
  void onDefinition(uint8_t op, const uint8_t* p, size_t n, const std::string& where);
  void resolveSchemas();
  Buffer chunk(const ChunkRef& ref);
  const ChunkRef& chunkAt(uint64_t offset) const;

  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0;
  bool indexed_ = false, truncated_ = false;
  std::map<uint16_t, McapChannel> channels_;
  std::map<uint16_t, std::array<std::string, 3>> schemas_;  // id -> name, encoding, data
  std::vector<ChunkRef> chunks_;
  std::set<uint64_t> verified_;  // file offsets of the chunks whose CRC has been checked
  std::vector<std::pair<uint64_t, Buffer>> cache_;  // decompressed chunks by file offset, newest last
};

}  // namespace ff

#include "flowfusion/io/mcap_writer.h"

#include "flowfusion/core/error.h"

#ifdef FLOWFUSION_HAVE_ROS2BAG

#include <zstd.h>

#include <algorithm>

#include "flowfusion/io/crc32.h"

namespace ff {

namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";
constexpr int kZstdLevel = 3;
enum Op : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kMessageIndex = 0x07, kChunkIndex = 0x08, kStatistics = 0x0B, kDataEnd = 0x0F
};

// Little-endian record fields.
struct Fields {
  std::string b;
  Fields& u8(uint8_t v) { return uint(v, 1); }
  Fields& u16(uint16_t v) { return uint(v, 2); }
  Fields& u32(uint32_t v) { return uint(v, 4); }
  Fields& u64(uint64_t v) { return uint(v, 8); }
  Fields& uint(uint64_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) b += char((v >> (8 * i)) & 0xFF);
    return *this;
  }
  Fields& str(const std::string& s) {
    u32(uint32_t(s.size()));
    b += s;
    return *this;
  }
};

std::string record(uint8_t op, const std::string& content) {
  Fields f;
  f.u8(op).u64(content.size());
  return f.b + content;
}

}  // namespace

bool mcapWriterBuilt() { return true; }

McapFileWriter::McapFileWriter(const std::string& path, size_t chunk_bytes)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc), chunk_bytes_(chunk_bytes) {
  if (!out_) throw InputError(path + ": cannot create the MCAP file");
  const std::string magic(kMagic, 8);
  out_ << magic;
  offset_ = magic.size();
  data_crc_ = crc32(reinterpret_cast<const uint8_t*>(magic.data()), magic.size());
  put(record(kHeader, Fields().str("").str("flowfusion").b));
}

McapFileWriter::~McapFileWriter() {
  if (closed_) return;
  try {
    close();
  } catch (const std::exception&) {  // a destructor must not throw; close() reports errors to callers that call it
  }
}

void McapFileWriter::put(const std::string& r) {
  out_.write(r.data(), std::streamsize(r.size()));
  data_crc_ = crc32(reinterpret_cast<const uint8_t*>(r.data()), r.size(), data_crc_);
  offset_ += r.size();
}

uint16_t McapFileWriter::addSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  const auto id = uint16_t(schemas_.size() + 1);
  schemas_.push_back(record(kSchema, Fields().u16(id).str(name).str(encoding).str(data).b));
  put(schemas_.back());
  return id;
}

uint16_t McapFileWriter::addChannel(const std::string& topic, uint16_t schema, const std::string& message_encoding) {
  const auto id = uint16_t(channels_.size() + 1);
  channels_.push_back(record(kChannel, Fields().u16(id).u16(schema).str(topic).str(message_encoding).u32(0).b));
  put(channels_.back());
  counts_[id] = 0;
  return id;
}

void McapFileWriter::write(uint16_t channel, uint64_t log_time_ns, const std::string& data) {
  if (chunk_.empty()) chunk_start_ns_ = chunk_end_ns_ = log_time_ns;
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  chunk_index_[channel].emplace_back(log_time_ns, chunk_.size());
  chunk_ += record(kMessage, Fields().u16(channel).u32(uint32_t(counts_[channel])).u64(log_time_ns).u64(log_time_ns).b + data);
  ++counts_[channel];
  first_ns_ = messages_ == 0 ? log_time_ns : std::min(first_ns_, log_time_ns);
  last_ns_ = messages_ == 0 ? log_time_ns : std::max(last_ns_, log_time_ns);
  ++messages_;
  if (chunk_.size() >= chunk_bytes_) flushChunk();
}

// The open chunk compressed with zstd, then one message index per channel in it.
void McapFileWriter::flushChunk() {
  if (chunk_.empty()) return;
  std::string compressed(ZSTD_compressBound(chunk_.size()), '\0');
  const size_t n = ZSTD_compress(compressed.data(), compressed.size(), chunk_.data(), chunk_.size(), kZstdLevel);
  if (ZSTD_isError(n)) throw InputError(path_ + ": zstd failed: " + ZSTD_getErrorName(n));
  compressed.resize(n);
  ChunkIndex index{chunk_start_ns_, chunk_end_ns_, offset_, 0, 0, 0, n, chunk_.size(), {}};
  const uint32_t crc = crc32(reinterpret_cast<const uint8_t*>(chunk_.data()), chunk_.size());
  put(record(kChunk, Fields().u64(chunk_start_ns_).u64(chunk_end_ns_).u64(chunk_.size()).u32(crc).str("zstd").u64(n).b +
                         compressed));
  index.length = offset_ - index.offset;
  index.index_offset = offset_;
  for (const auto& [channel, entries] : chunk_index_) {
    Fields f;
    f.u16(channel).u32(uint32_t(entries.size() * 16));
    for (const auto& [t, at] : entries) f.u64(t).u64(at);
    index.message_index_offsets[channel] = offset_;
    put(record(kMessageIndex, f.b));
  }
  index.index_length = offset_ - index.index_offset;
  chunks_.push_back(index);
  chunk_.clear();
  chunk_index_.clear();
}

void McapFileWriter::close() {
  if (closed_) return;
  closed_ = true;
  flushChunk();
  put(record(kDataEnd, Fields().u32(data_crc_).b));
  const uint64_t summary_start = offset_;
  std::string summary;
  for (const std::string& s : schemas_) summary += s;
  for (const std::string& c : channels_) summary += c;
  for (const ChunkIndex& c : chunks_) {
    Fields offsets;
    for (const auto& [channel, at] : c.message_index_offsets) offsets.u16(channel).u64(at);
    summary += record(kChunkIndex, Fields().u64(c.start_ns).u64(c.end_ns).u64(c.offset).u64(c.length)
                                       .u32(uint32_t(offsets.b.size())).b + offsets.b +
                                       Fields().u64(c.index_length).str("zstd").u64(c.compressed).u64(c.uncompressed).b);
  }
  Fields counts;
  for (const auto& [channel, n] : counts_) counts.u16(channel).u64(n);
  summary += record(kStatistics, Fields().u64(messages_).u16(uint16_t(schemas_.size())).u32(uint32_t(channels_.size()))
                                     .u32(0).u32(0).u32(uint32_t(chunks_.size())).u64(first_ns_).u64(last_ns_)
                                     .u32(uint32_t(counts.b.size())).b + counts.b);
  const std::string footer_start = Fields().u8(kFooter).u64(20).u64(summary_start).u64(0).b;
  const uint32_t crc = crc32(reinterpret_cast<const uint8_t*>(footer_start.data()), footer_start.size(),
                             crc32(reinterpret_cast<const uint8_t*>(summary.data()), summary.size()));
  out_ << summary << footer_start << Fields().u32(crc).b << std::string(kMagic, 8);
  out_.close();
  if (!out_) throw InputError(path_ + ": writing the MCAP file failed (disk full?)");
}

}  // namespace ff

#else  // FLOWFUSION_HAVE_ROS2BAG

namespace ff {

bool mcapWriterBuilt() { return false; }

// No McapFileWriter exists in this build (the constructor throws), so none of the others is reached.
McapFileWriter::McapFileWriter(const std::string& path, size_t) {
  throw InputError(path + ": this flowfusion was built without MCAP support; install Debian's libzstd-dev, "
                          "liblz4-dev and libsqlite3-dev (bash scripts/install-deps.sh), configure and build again");
}
McapFileWriter::~McapFileWriter() = default;
uint16_t McapFileWriter::addSchema(const std::string&, const std::string&, const std::string&) { return 0; }
uint16_t McapFileWriter::addChannel(const std::string&, uint16_t, const std::string&) { return 0; }
void McapFileWriter::write(uint16_t, uint64_t, const std::string&) {}
void McapFileWriter::close() {}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROS2BAG

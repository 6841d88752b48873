#include "flowfusion/io/mcap_reader.h"

// Built with the ROS 2 bag readers only (cmake/FlowfusionRos2Bag.cmake).
#ifdef FLOWFUSION_HAVE_ROS2BAG

#include <fcntl.h>
#include <lz4frame.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>

#include "flowfusion/core/error.h"
#include "flowfusion/io/crc32.h"

namespace ff {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr size_t kMagicBytes = 8, kRecordHeader = 9, kFooterBytes = kRecordHeader + 20;
constexpr uint64_t kMaxChunkBytes = uint64_t(1) << 32;  // a larger uncompressed size is corrupt
enum Op : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kChunkIndex = 0x08, kDataEnd = 0x0F
};
constexpr size_t kMessagePrefix = 2 + 4 + 8 + 8;  // channel, sequence, log and publish times

struct ParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Little-endian fields of one record's content, bounds-checked.
class Fields {
 public:
  Fields(const uint8_t* p, size_t n) : p_(p), n_(n) {}
  uint64_t uint(size_t bytes) {
    const uint8_t* q = take(bytes);
    uint64_t v = 0;
    for (size_t i = bytes; i-- > 0;) v = v << 8 | q[i];
    return v;
  }
  std::string str() {
    const size_t len = size_t(uint(4));
    return std::string(reinterpret_cast<const char*>(take(len)), len);
  }
  const uint8_t* take(size_t bytes) {
    if (bytes > n_ - pos_) throw ParseError("record ends inside a field");
    const uint8_t* q = p_ + pos_;
    pos_ += bytes;
    return q;
  }
  size_t left() const { return n_ - pos_; }

 private:
  const uint8_t* p_;
  size_t n_, pos_ = 0;
};

// Calls f(opcode, content, content bytes, record offset in p) for each record of p[0, n).
template <class F>
void forEachRecord(const uint8_t* p, size_t n, F&& f) {
  for (size_t pos = 0; pos < n;) {
    if (n - pos < kRecordHeader) throw ParseError("a record header is cut short at byte " + std::to_string(pos));
    Fields h(p + pos, kRecordHeader);
    const uint8_t op = uint8_t(h.uint(1));
    const uint64_t len = h.uint(8);
    if (len > n - pos - kRecordHeader)
      throw ParseError("record of " + std::to_string(len) + " bytes at byte " + std::to_string(pos) + " overruns");
    f(op, p + pos + kRecordHeader, size_t(len), pos);
    pos += kRecordHeader + size_t(len);
  }
}

void lz4Decompress(const uint8_t* src, size_t n, uint8_t* dst, size_t size) {
  LZ4F_dctx* ctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&ctx, LZ4F_VERSION))) throw ParseError("lz4: no context");
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> owner(ctx, LZ4F_freeDecompressionContext);
  size_t src_left = n, dst_left = size;
  for (;;) {
    size_t in = src_left, out = dst_left;
    const size_t r = LZ4F_decompress(ctx, dst, &out, src, &in, nullptr);
    if (LZ4F_isError(r)) throw ParseError(std::string("lz4 chunk does not decompress: ") + LZ4F_getErrorName(r));
    src += in, src_left -= in, dst += out, dst_left -= out;
    if (r == 0) break;
    if (in == 0 && out == 0) throw ParseError("lz4 chunk ends before its frame does");
  }
  if (dst_left != 0) throw ParseError("lz4 chunk is shorter than its declared uncompressed size");
}

// A chunk record's content decompressed; its CRC checked when written and `check_crc`.
std::vector<uint8_t> decompressChunk(const uint8_t* p, size_t n, bool check_crc = true) {
  Fields f(p, n);
  f.uint(8), f.uint(8);  // message start and end times
  const uint64_t size = f.uint(8);
  const uint32_t crc = uint32_t(f.uint(4));
  const std::string compression = f.str();
  const uint64_t stored = f.uint(8);
  if (stored > f.left()) throw ParseError("chunk's records overrun the chunk");
  if (size > kMaxChunkBytes) throw ParseError("chunk declares " + std::to_string(size) + " uncompressed bytes");
  const uint8_t* src = f.take(size_t(stored));
  std::vector<uint8_t> out(size);
  if (compression.empty()) {
    if (stored != size) throw ParseError("uncompressed chunk's size disagrees with its records");
    std::copy(src, src + stored, out.begin());
  } else if (compression == "zstd") {
    const size_t r = ZSTD_decompress(out.data(), out.size(), src, size_t(stored));
    if (ZSTD_isError(r)) throw ParseError(std::string("zstd chunk does not decompress: ") + ZSTD_getErrorName(r));
    if (r != size) throw ParseError("zstd chunk is shorter than its declared uncompressed size");
  } else if (compression == "lz4") {
    lz4Decompress(src, size_t(stored), out.data(), out.size());
  } else {
    throw ParseError("chunk compression '" + compression + "' is not one of none, zstd, lz4");
  }
  if (check_crc && crc != 0 && crc32(out.data(), out.size()) != crc) throw ParseError("chunk CRC does not match its records (corrupt)");
  return out;
}

}  // namespace

void McapReader::fail(const std::string& message) const { throw InputError(path_ + ": " + message); }

McapReader::McapReader(std::string path) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) fail("cannot open the MCAP file (" + std::string(std::strerror(errno)) + ")");
  try {
    readStart();
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

// The file's magic and version, then its channels and chunks from the summary or a linear scan.
void McapReader::readStart() {
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) fail("is not a regular file; an MCAP file is read from a file on disk");
  size_ = uint64_t(st.st_size);
  uint8_t magic[kMagicBytes] = {};
  if (size_ < kMagicBytes) fail("not an MCAP file (" + std::to_string(size_) + " bytes, shorter than its magic)");
  read(0, kMagicBytes, magic);
  if (std::memcmp(magic, kMagic, 5) != 0 || magic[6] != '\r' || magic[7] != '\n') fail("not an MCAP file (no MCAP magic)");
  if (magic[5] != '0')
    fail(std::string("MCAP format version '") + char(magic[5]) + "' is not supported (this reader reads version 0)");
  try {
    if (!readSummary()) scanLinear();
    resolveSchemas();
  } catch (const ParseError& e) {
    fail(std::string("corrupt MCAP file: ") + e.what());
  }
}

McapReader::~McapReader() {
  if (fd_ >= 0) ::close(fd_);
}

void McapReader::read(uint64_t offset, size_t n, uint8_t* out) const {
  if (offset > size_ || n > size_ - offset)
    fail("record at byte " + std::to_string(offset) + " reaches past the end of the file (truncated?)");
  for (size_t done = 0; done < n;) {
    const ssize_t r = ::pread(fd_, out + done, n - done, off_t(offset + done));
    if (r <= 0) fail("reading failed at byte " + std::to_string(offset + done) + " (" + std::strerror(errno) + ")");
    done += size_t(r);
  }
}

std::vector<uint8_t> McapReader::read(uint64_t offset, size_t n) const {
  std::vector<uint8_t> out(n);
  read(offset, n, out.data());
  return out;
}

void McapReader::onDefinition(uint8_t op, const uint8_t* p, size_t n, const std::string& where) {
  Fields f(p, n);
  if (op == kSchema) {
    const auto id = uint16_t(f.uint(2));
    std::string name = f.str(), encoding = f.str(), data = f.str();
    schemas_[id] = {std::move(name), std::move(encoding), std::move(data)};
  } else if (op == kChannel) {
    McapChannel c;
    c.id = uint16_t(f.uint(2));
    const auto schema = uint16_t(f.uint(2));
    c.topic = f.str();
    c.message_encoding = f.str();
    c.schema_id = schema;  // 0: none; resolved once every schema is known
    if (channels_.count(c.id) && channels_[c.id].topic != c.topic)
      throw ParseError(where + ": channel " + std::to_string(c.id) + " is declared for two topics");
    channels_[c.id] = c;
  }
}

void McapReader::resolveSchemas() {
  for (auto& [id, c] : channels_) {
    if (c.schema_id == 0) continue;
    const auto it = schemas_.find(c.schema_id);
    if (it == schemas_.end())
      throw ParseError("channel " + c.topic + " names schema " + std::to_string(c.schema_id) + ", which is not in the file");
    c.schema_name = it->second[0];
    c.schema_encoding = it->second[1];
    c.schema_data = it->second[2];
  }
}

// The summary section through the footer: channels, schemas and chunk indexes. False when the
// file has no footer (cut short) or no chunk indexes, which the linear scan then finds.
bool McapReader::readSummary() {
  if (size_ < 2 * kMagicBytes + kFooterBytes) return false;
  const uint64_t footer_at = size_ - kMagicBytes - kFooterBytes;
  const std::vector<uint8_t> tail = read(footer_at, kFooterBytes + kMagicBytes);
  if (std::memcmp(tail.data() + kFooterBytes, kMagic, kMagicBytes) != 0 || tail[0] != kFooter) return false;
  Fields f(tail.data() + kRecordHeader, 20);
  const uint64_t summary_start = f.uint(8);
  f.uint(8);  // summary offset section
  const auto summary_crc = uint32_t(f.uint(4));
  if (summary_start == 0) return false;
  if (summary_start < kMagicBytes || summary_start > footer_at)
    fail("the footer's summary start " + std::to_string(summary_start) + " lies outside the file (corrupt)");
  const std::vector<uint8_t> summary = read(summary_start, size_t(footer_at - summary_start));
  if (summary_crc != 0 && crc32(tail.data(), kRecordHeader + 16, crc32(summary.data(), summary.size())) != summary_crc)
    fail("the summary section's CRC does not match (corrupt)");
  std::vector<ChunkRef> chunks;
  forEachRecord(summary.data(), summary.size(), [&](uint8_t op, const uint8_t* p, size_t n, size_t) {
    if (op == kSchema || op == kChannel) onDefinition(op, p, n, "summary");
    if (op != kChunkIndex) return;
    Fields c(p, n);
    c.uint(8), c.uint(8);  // message start and end times
    ChunkRef ref;
    ref.offset = c.uint(8);
    ref.length = c.uint(8);
    const uint64_t index_bytes = c.uint(4);
    if (index_bytes % 10 != 0 || index_bytes > c.left()) throw ParseError("chunk index's message index map is malformed");
    for (uint64_t k = 0; k < index_bytes / 10; ++k) {
      ref.channels.insert(uint16_t(c.uint(2)));
      c.uint(8);
    }
    if (ref.offset < kMagicBytes || ref.offset > size_ || ref.length > size_ - ref.offset)
      throw ParseError("chunk index points outside the file");
    chunks.push_back(ref);
  });
  if (chunks.empty()) {
    channels_.clear();
    schemas_.clear();
    return false;
  }
  std::sort(chunks.begin(), chunks.end(), [](const ChunkRef& a, const ChunkRef& b) { return a.offset < b.offset; });
  chunks_ = std::move(chunks);
  indexed_ = true;
  return true;
}

// Every record from the magic on: the definitions (inside chunks too), where each chunk and loose
// message is, the data section's CRC. Stops at the first record cut short (a crash's file).
void McapReader::scanLinear() {
  uint64_t pos = kMagicBytes;
  uint32_t crc = crc32(kMagic, kMagicBytes);
  while (pos < size_) {
    if (size_ - pos < kRecordHeader) {
      truncated_ = true;
      break;
    }
    std::vector<uint8_t> header = read(pos, kRecordHeader);
    Fields h(header.data(), kRecordHeader);
    const uint8_t op = uint8_t(h.uint(1));
    const uint64_t len = h.uint(8);
    if (len > size_ - pos - kRecordHeader) {
      truncated_ = true;
      break;
    }
    if (op == kFooter) break;
    const std::vector<uint8_t> content = read(pos + kRecordHeader, size_t(len));
    if (op == kDataEnd) {
      const auto written = uint32_t(Fields(content.data(), content.size()).uint(4));
      if (written != 0 && written != crc) fail("the data section's CRC does not match (corrupt)");
      break;
    }
    crc = crc32(content.data(), content.size(), crc32(header.data(), header.size(), crc));
    const std::string where = "record at byte " + std::to_string(pos);
    if (op == kSchema || op == kChannel) onDefinition(op, content.data(), content.size(), where);
    if (op == kChunk) {
      ChunkRef ref{pos, kRecordHeader + len, {}, false};
      const std::vector<uint8_t> records = decompressChunk(content.data(), content.size());
      verified_.insert(pos);
      forEachRecord(records.data(), records.size(), [&](uint8_t inner, const uint8_t* p, size_t n, size_t) {
        if (inner == kSchema || inner == kChannel) onDefinition(inner, p, n, where);
        if (inner == kMessage) ref.channels.insert(uint16_t(Fields(p, n).uint(2)));
      });
      chunks_.push_back(std::move(ref));
    } else if (op == kMessage) {
      chunks_.push_back({pos, kRecordHeader + len, {uint16_t(Fields(content.data(), content.size()).uint(2))}, true});
    } else if (op == kHeader && pos != kMagicBytes) {
      throw ParseError("a second header record at byte " + std::to_string(pos));
    }
    pos += kRecordHeader + len;
  }
}

McapReader::Buffer McapReader::chunk(const ChunkRef& ref) {
  for (const auto& [offset, buffer] : cache_)
    if (offset == ref.offset) return buffer;
  const std::vector<uint8_t> record = read(ref.offset, size_t(ref.length));
  if (record.size() < kRecordHeader || record[0] != kChunk) fail("chunk index points at byte " + std::to_string(ref.offset) + ", which holds no chunk (corrupt)");
  Buffer out;
  try {
    // Each chunk's CRC is checked the first time it is decompressed, not on every read.
    out = std::make_shared<std::vector<uint8_t>>(decompressChunk(
        record.data() + kRecordHeader, record.size() - kRecordHeader, verified_.count(ref.offset) == 0));
    verified_.insert(ref.offset);
  } catch (const ParseError& e) {
    fail("chunk at byte " + std::to_string(ref.offset) + ": " + e.what());
  }
  cache_.emplace_back(ref.offset, out);
  if (cache_.size() > 2) cache_.erase(cache_.begin());
  return out;
}

const McapReader::ChunkRef& McapReader::chunkAt(uint64_t offset) const {
  const auto it = std::lower_bound(chunks_.begin(), chunks_.end(), offset,
                                   [](const ChunkRef& c, uint64_t o) { return c.offset < o; });
  if (it == chunks_.end() || it->offset != offset) fail("no chunk at byte " + std::to_string(offset));
  return *it;
}

void McapReader::scan(const std::set<uint16_t>& channels,
                      const std::function<bool(const McapMessage&, const McapLocation&)>& visit) {
  for (const ChunkRef& ref : chunks_) {
    const bool wanted = ref.channels.empty() || std::any_of(ref.channels.begin(), ref.channels.end(),
                                                            [&](uint16_t c) { return channels.count(c) > 0; });
    if (!wanted) continue;
    if (ref.loose) {
      const McapMessage m = message({McapLocation::kNoChunk, ref.offset});
      if (!visit(m, {McapLocation::kNoChunk, ref.offset})) return;
      continue;
    }
    const Buffer records = chunk(ref);
    bool go_on = true;
    try {
      forEachRecord(records->data(), records->size(), [&](uint8_t op, const uint8_t* p, size_t n, size_t at) {
        if (op != kMessage || !go_on) return;
        if (n < kMessagePrefix) throw ParseError("message record of " + std::to_string(n) + " bytes");
        const auto channel = uint16_t(Fields(p, n).uint(2));
        if (channels.count(channel))
          go_on = visit({channel, p + kMessagePrefix, n - kMessagePrefix, records}, {ref.offset, at});
      });
    } catch (const ParseError& e) {
      fail("chunk at byte " + std::to_string(ref.offset) + ": " + e.what());
    }
    if (!go_on) return;
  }
}

McapMessage McapReader::message(const McapLocation& where) {
  Buffer records;
  uint64_t at = where.offset;
  if (where.chunk == McapLocation::kNoChunk) {
    const ChunkRef& ref = chunkAt(where.offset);
    records = std::make_shared<std::vector<uint8_t>>(read(ref.offset, size_t(ref.length)));
    at = 0;
  } else {
    records = chunk(chunkAt(where.chunk));
  }
  McapMessage m;
  try {
    Fields h(records->data() + std::min<uint64_t>(at, records->size()), records->size() - std::min<uint64_t>(at, records->size()));
    if (h.uint(1) != kMessage) throw ParseError("no message record at its location");
    const uint64_t len = h.uint(8);
    if (len < kMessagePrefix || len > h.left()) throw ParseError("message record overruns its chunk");
    Fields f(h.take(size_t(len)), size_t(len));
    m.channel = uint16_t(f.uint(2));
    f.take(kMessagePrefix - 2);
    m.size = f.left();
    m.data = f.take(m.size);
  } catch (const ParseError& e) {
    fail("message at byte " + std::to_string(where.offset) + ": " + e.what());
  }
  m.keep = records;
  return m;
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_ROS2BAG

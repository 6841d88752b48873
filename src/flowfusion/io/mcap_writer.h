#pragma once
// MCAP files written (format version 0, the layout io/mcap_reader.h reads): schemas and channels,
// messages in zstd chunks of about `chunk_bytes` each followed by their message indexes, then a
// summary (schemas, channels, chunk indexes, statistics) with its CRC and the footer, so that a
// reader seeks to any channel without reading the whole file. Foxglove opens such files.
// Needs libzstd (FLOWFUSION_HAVE_ROS2BAG); without it the constructor throws an InputError
// saying how to enable it (mcapWriterBuilt()).
#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace ff {

bool mcapWriterBuilt();

class McapFileWriter {
 public:
  // Creates `path` (replacing it); InputError when it cannot be written.
  explicit McapFileWriter(const std::string& path, size_t chunk_bytes = 4 << 20);
  ~McapFileWriter();  // closes the file (summary and footer) unless close() was called or it failed
  McapFileWriter(const McapFileWriter&) = delete;
  McapFileWriter& operator=(const McapFileWriter&) = delete;

  uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t addChannel(const std::string& topic, uint16_t schema, const std::string& message_encoding);
  // One message; log_time_ns: nanoseconds since the epoch (the frame's stamp).
  void write(uint16_t channel, uint64_t log_time_ns, const std::string& data);
  // Flushes the last chunk, writes the data end, summary and footer. InputError on a write error.
  void close();
  const std::string& path() const { return path_; }

 private:
  struct ChunkIndex {
    uint64_t start_ns = 0, end_ns = 0, offset = 0, length = 0, index_offset = 0, index_length = 0;
    uint64_t compressed = 0, uncompressed = 0;
    std::map<uint16_t, uint64_t> message_index_offsets;
  };
  void put(const std::string& record);  // top level, counted in the data section's CRC
  void flushChunk();

  std::string path_;
  std::ofstream out_;
  size_t chunk_bytes_;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;
  bool closed_ = false;
  std::vector<std::string> schemas_, channels_;  // their records, repeated in the summary
  std::string chunk_;                            // records of the open chunk
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  // channel: (time, offset)
  uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  std::vector<ChunkIndex> chunks_;
  std::map<uint16_t, uint64_t> counts_;  // messages per channel
  uint64_t messages_ = 0, first_ns_ = 0, last_ns_ = 0;
};

}  // namespace ff

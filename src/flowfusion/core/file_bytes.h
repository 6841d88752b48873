#pragma once
// Whole files read into memory, and the big-endian numbers of the binary formats read from them
// (PNG, the saved map): one reader, so that every format refuses an unreadable file alike.
#include <cstdint>
#include <optional>
#include <string>

namespace ff {

// The bytes of the regular file at `path`; nullopt when there is none or it cannot be read.
std::optional<std::string> readFileBytes(const std::string& path);

// The unsigned 32-bit number stored most significant byte first at `p`.
inline uint32_t bigEndian32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

}  // namespace ff

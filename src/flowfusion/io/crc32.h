#pragma once
// CRC-32 (IEEE 802.3, as zlib's crc32) for the MCAP files' chunk, data and summary checksums:
// eight bytes a step (slicing-by-8), since chunk CRCs cover every decompressed byte.
#include <cstddef>
#include <cstdint>

namespace ff {

// The CRC of p[0, n) continued from `crc` (0 to start).
uint32_t crc32(const uint8_t* p, size_t n, uint32_t crc = 0);

}  // namespace ff

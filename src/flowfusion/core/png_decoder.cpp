#include "flowfusion/core/png_decoder.h"

#ifdef FLOWFUSION_HAVE_LIBDEFLATE

#include <libdeflate.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string_view>

#include "flowfusion/core/file_bytes.h"

namespace ff {

namespace {

struct PngHeader {
  uint32_t width = 0, height = 0;
  int channels = 0;        // 1 grey, 3 colour
  int bytes_per_sample = 0;  // 1 or 2
  size_t pixelBytes() const { return static_cast<size_t>(channels) * bytes_per_sample; }
  size_t rowBytes() const { return width * pixelBytes(); }
};

// IHDR's 13 bytes, when they describe a kind this decoder handles.
std::optional<PngHeader> parseHeader(const unsigned char* d) {
  PngHeader h;
  h.width = bigEndian32(d);
  h.height = bigEndian32(d + 4);
  const int bit_depth = d[8], colour_type = d[9];
  const bool plain = d[10] == 0 && d[11] == 0 && d[12] == 0;  // deflate, adaptive filters, not interlaced
  if (!plain || (bit_depth != 8 && bit_depth != 16) || (colour_type != 0 && colour_type != 2)) return std::nullopt;
  if (h.width == 0 || h.height == 0 || h.width > (1u << 26) || h.height > (1u << 26)) return std::nullopt;
  h.channels = colour_type == 2 ? 3 : 1;
  h.bytes_per_sample = bit_depth / 8;
  return h;
}

// The header and the IDAT chunks' contents in order (the zlib stream), each chunk's CRC checked.
std::optional<std::vector<unsigned char>> readChunks(std::string_view file, PngHeader& header) {
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto* f = reinterpret_cast<const unsigned char*>(file.data());
  const size_t size = file.size();
  if (size < 8 || std::memcmp(f, kSignature, 8) != 0) return std::nullopt;
  std::vector<unsigned char> stream;
  bool have_header = false, in_data = false, data_done = false;
  for (size_t p = 8; p + 12 <= size;) {
    const uint32_t n = bigEndian32(f + p);
    if (n > size - p - 12) return std::nullopt;
    const unsigned char* type = f + p + 4;
    const unsigned char* data = type + 4;
    const std::string_view name(reinterpret_cast<const char*>(type), 4);
    if (name == "IEND") return have_header && (in_data || data_done) ? std::optional(std::move(stream)) : std::nullopt;
    const bool header_chunk = name == "IHDR", data_chunk = name == "IDAT";
    if (header_chunk || data_chunk) {
      if (libdeflate_crc32(libdeflate_crc32(0, type, 4), data, n) != bigEndian32(data + n)) return std::nullopt;
    } else if (!(type[0] & 0x20) || name == "tRNS") {
      return std::nullopt;  // a critical chunk (PLTE, ...) or transparency: OpenCV's
    }
    if (header_chunk) {
      if (have_header || n != 13) return std::nullopt;
      const std::optional<PngHeader> h = parseHeader(data);
      if (!h) return std::nullopt;
      header = *h;
      have_header = true;
    } else if (data_chunk) {
      if (!have_header || data_done) return std::nullopt;
      stream.insert(stream.end(), data, data + n);
      in_data = true;
    } else if (in_data) {
      in_data = false;
      data_done = true;
    }
    p += 12 + size_t{n};
  }
  return std::nullopt;  // no IEND
}

inline int paeth(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  const int b_or_c = pb <= pc ? b : c;
  return pa <= pb && pa <= pc ? a : b_or_c;
}

// The Paeth filter undone for pixels of kBpp bytes, the left and upper-left pixels kept in
// registers: each byte depends on the one kBpp before, and through memory that chain waited for
// every store (Paeth is most rows of TUM's colour images; the first pixel's neighbours are 0).
template <int kBpp>
bool paethRow(unsigned char* row, const unsigned char* up, size_t n) {
  std::array<int, kBpp> left{}, up_left{};
  for (size_t i = 0; i < n; i += kBpp)
    for (int k = 0; k < kBpp; ++k) {
      const int above = up[i + k];
      const int value = (row[i + k] + paeth(left[k], above, up_left[k])) & 0xff;
      row[i + k] = static_cast<unsigned char>(value);
      left[k] = value;
      up_left[k] = above;
    }
  return true;
}

// Undoes scanline `row`'s filter in place, given the row above (zeros for the first); false for
// an unknown filter type.
bool unfilter(int type, unsigned char* row, const unsigned char* up, size_t n, size_t bpp) {
  switch (type) {
    case 0:
      return true;
    case 1:
      for (size_t i = bpp; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + row[i - bpp]);
      return true;
    case 2:
      for (size_t i = 0; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + up[i]);
      return true;
    case 3:
      for (size_t i = 0; i < bpp; ++i) row[i] = static_cast<unsigned char>(row[i] + (up[i] >> 1));
      for (size_t i = bpp; i < n; ++i) row[i] = static_cast<unsigned char>(row[i] + ((row[i - bpp] + up[i]) >> 1));
      return true;
    case 4:
      switch (bpp) {
        case 1: return paethRow<1>(row, up, n);
        case 2: return paethRow<2>(row, up, n);
        case 3: return paethRow<3>(row, up, n);
        case 6: return paethRow<6>(row, up, n);
        default: return false;
      }
    default:
      return false;
  }
}

// One unfiltered scanline into an image row as OpenCV has it: BGR, native-endian 16-bit.
void storeRow(const PngHeader& h, const unsigned char* s, unsigned char* out) {
  const size_t samples = static_cast<size_t>(h.width) * h.channels;
  if (h.bytes_per_sample == 2) {
    auto* o = reinterpret_cast<uint16_t*>(out);
    const size_t step = h.channels;
    for (size_t i = 0; i < samples; i += step)
      for (size_t k = 0; k < step; ++k) {
        const size_t from = h.channels == 3 ? i + 2 - k : i + k;
        o[i + k] = static_cast<uint16_t>((s[2 * from] << 8) | s[2 * from + 1]);
      }
  } else if (h.channels == 3) {
    for (size_t i = 0; i < samples; i += 3) {
      out[i] = s[i + 2];
      out[i + 1] = s[i + 1];
      out[i + 2] = s[i];
    }
  } else {
    std::memcpy(out, s, samples);
  }
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

}  // namespace

std::optional<cv::Mat> decodeSimplePng(std::string_view file) {
  PngHeader h;
  const std::optional<std::vector<unsigned char>> stream = readChunks(file, h);
  if (!stream) return std::nullopt;
  const size_t row_bytes = h.rowBytes(), line = row_bytes + 1;  // each scanline: filter type, then the row
  std::vector<unsigned char> lines(line * h.height);
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor(
      libdeflate_alloc_decompressor());
  size_t inflated = 0;
  if (!decompressor || libdeflate_zlib_decompress(decompressor.get(), stream->data(), stream->size(), lines.data(),
                                                  lines.size(), &inflated) != LIBDEFLATE_SUCCESS ||
      inflated != lines.size())
    return std::nullopt;
  cv::Mat image(static_cast<int>(h.height), static_cast<int>(h.width),
                CV_MAKETYPE(h.bytes_per_sample == 2 ? CV_16U : CV_8U, h.channels));
  const std::vector<unsigned char> zeros(row_bytes, 0);
  for (uint32_t y = 0; y < h.height; ++y) {
    unsigned char* row = &lines[y * line + 1];
    const unsigned char* up = y == 0 ? zeros.data() : row - line;
    if (!unfilter(row[-1], row, up, row_bytes, h.pixelBytes())) return std::nullopt;
    storeRow(h, row, image.ptr(static_cast<int>(y)));
  }
  return image;
}

}  // namespace ff

#endif  // FLOWFUSION_HAVE_LIBDEFLATE

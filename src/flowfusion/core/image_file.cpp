#include "flowfusion/core/image_file.h"

#include <array>
#include <cstring>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/core/file_bytes.h"
#include "flowfusion/core/png_decoder.h"

namespace ff {

namespace {

std::string sizeText(long long w, long long h) { return std::to_string(w) + "x" + std::to_string(h); }

}  // namespace

std::optional<cv::Size> readPngSize(const std::string& path) {
  // Signature (8 bytes), IHDR length (4) and type (4), then width and height (4 + 4, big-endian).
  std::array<unsigned char, 24> head{};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size())) return std::nullopt;
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (std::memcmp(head.data(), kSignature, 8) != 0 || std::memcmp(head.data() + 12, "IHDR", 4) != 0)
    return std::nullopt;
  const uint32_t w = bigEndian32(head.data() + 16), h = bigEndian32(head.data() + 20);
  // PNG limits each side to 2^31 - 1; clamp so that cv::Size holds whatever the file says.
  const auto side = [](uint32_t v) { return static_cast<int>(std::min<uint32_t>(v, 0x7fffffff)); };
  return cv::Size(side(w), side(h));
}

cv::Mat readImageFile(const std::string& path, int flags, const std::string& what, cv::Size expected) {
  if (const auto size = readPngSize(path)) {
    if (!expected.empty() && *size != expected)
      throw InputError(path + ": " + what + " is " + sizeText(size->width, size->height) + ", expected " +
                       sizeText(expected.width, expected.height));
    if (static_cast<long long>(size->width) * size->height > kMaxImagePixels)
      throw InputError(path + ": " + what + " declares " + sizeText(size->width, size->height) +
                       " pixels, more than the " + std::to_string(kMaxImagePixels) + " this program decodes");
#ifdef FLOWFUSION_HAVE_LIBDEFLATE
    if (flags == cv::IMREAD_UNCHANGED)
      if (const std::optional<std::string> bytes = readFileBytes(path))
        if (std::optional<cv::Mat> image = decodeSimplePng(*bytes)) return std::move(*image);
#endif
  }
  try {
    return cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    throw InputError(path + ": cannot decode " + what + ": " + e.err);
  }
}

}  // namespace ff

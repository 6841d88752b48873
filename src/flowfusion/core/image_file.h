#pragma once
// Image files read with their size checked first: a PNG's header is read before anything is
// decoded, so a file declaring a huge image (100000x100000) or one of the wrong size is refused
// before its pixels are allocated, and OpenCV's decoding errors become InputErrors.
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

namespace ff {

// Largest image decoded at all, pixels (64 Mpx: far above any RGB-D camera).
inline constexpr long long kMaxImagePixels = 1LL << 26;

// Width and height from a PNG's IHDR chunk; nullopt when the file is not a PNG.
std::optional<cv::Size> readPngSize(const std::string& path);

// cv::imread(path, flags) after the size checks: an InputError naming the file (and `what`) when
// the PNG header declares more than kMaxImagePixels or, when `expected` is non-empty, another
// size; an empty Mat when the file is missing or cannot be decoded (the caller's message says
// which file that is and what it should be). With libdeflate, plain 8- and 16-bit grey and colour
// PNGs read IMREAD_UNCHANGED come from our own decoder, the same image (core/png_decoder.h).
cv::Mat readImageFile(const std::string& path, int flags, const std::string& what, cv::Size expected = {});

}  // namespace ff

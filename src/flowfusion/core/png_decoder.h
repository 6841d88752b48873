#pragma once
// A PNG decoder for the kinds of image sequences are stored as (8- and 16-bit grey and colour, not
// interlaced), over libdeflate, which inflates about twice as fast as zlib: decoding was a fifth
// of a run's CPU time on TUM frames (colour and depth PNGs, ~12 ms a frame through cv::imread),
// on the read-ahead thread that shares the cores with the pipeline
// (docs/performance.md#loading-and-cpu-per-frame).
// Built only with libdeflate (FLOWFUSION_HAVE_LIBDEFLATE); every other PNG is left to OpenCV.
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string_view>

namespace ff {

// The image cv::imread(path, cv::IMREAD_UNCHANGED) gives for a PNG file's bytes (channels in BGR
// order, 16-bit samples in native byte order); nullopt for a PNG this decoder leaves to OpenCV
// (interlaced, palette, alpha, a transparency chunk, fewer than 8 bits a sample, an unknown
// critical chunk) and for one with any damage (a chunk's CRC, the zlib stream, the data's size),
// so that OpenCV gives its image or its error exactly as before.
std::optional<cv::Mat> decodeSimplePng(std::string_view file);

}  // namespace ff

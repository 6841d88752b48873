#pragma once
// Every file the project writes reaches its final name whole or not at all: it is written to a
// temporary name beside the target (same folder, so the rename cannot cross file systems), every
// write, flush and close is checked, and only then is it renamed into place. A full disk or any
// other failure is an InputError naming the file and the reason ("No space left on device"), and
// leaves neither a temporary file nor a short file under the final name.
#include <functional>
#include <string>
#include <string_view>

#include <opencv2/core/mat.hpp>

namespace ff {

// Writes `bytes` to `path` atomically; `what` names the file's role in messages ("trajectory file").
void writeFileAtomic(const std::string& path, std::string_view bytes, const std::string& what = "file");

// cv::imencode as PNG, then writeFileAtomic. Encoding failures are errors too.
void writePngAtomic(const std::string& path, const cv::Mat& image, const std::string& what = "image");

// For a library that writes only to a path it is given: `write` writes the file at the temporary
// path it receives and throws or returns false on failure (it should also check what it wrote,
// e.g. read it back, when the library does not check its own writes). The result must be a
// non-empty file; it is then renamed to `path`.
void writeThroughTempPath(const std::string& path, const std::function<bool(const std::string& temp_path)>& write,
                          const std::string& what = "file");

}  // namespace ff

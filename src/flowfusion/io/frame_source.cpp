#include "flowfusion/io/frame_source.h"

#include <filesystem>

#include "flowfusion/core/error.h"
#include "flowfusion/io/bag_source.h"
#include "flowfusion/io/tum_folder_source.h"

namespace ff {

FrameRange parseFrameRange(const std::string& text) {
  const auto colon = text.find(':');
  const auto bad = [&]() { return InputError("--frames '" + text + "': expected FIRST:LAST (frame indices, inclusive)"); };
  if (colon == std::string::npos) throw bad();
  const auto parse = [&](const std::string& s, int fallback) {
    if (s.empty()) return fallback;
    size_t used = 0;
    int v;
    try {
      v = std::stoi(s, &used);
    } catch (const std::exception&) {
      throw bad();
    }
    if (used != s.size() || v < 0) throw bad();
    return v;
  };
  FrameRange r;
  r.first = parse(text.substr(0, colon), 0);
  r.last = parse(text.substr(colon + 1), -1);
  if (r.last >= 0 && r.last < r.first) throw bad();
  return r;
}

std::unique_ptr<FrameSource> openFrameSource(const std::string& path, const SequenceOptions& options,
                                             FrameRange range) {
  if (std::filesystem::path(path).extension() == ".bag" || isRos2BagPath(path))
    return std::make_unique<BagSource>(path, options, range);
  return std::make_unique<TumFolderSource>(TumSequence::open(path, options), range);
}

}  // namespace ff

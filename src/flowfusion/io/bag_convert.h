#pragma once
// `flowfusion convert`: a ROS 1 or ROS 2 bag (io/bag_reader.h) written as a TUM-layout folder that any
// TUM tool reads: rgb/ (8-bit BGR PNG as recorded, not undistorted), depth/ (16-bit PNG at 5000
// units per metre, TUM's scale), rgb.txt and depth.txt (the header stamps), camera.txt (with the
// lens distortion when there is one) and groundtruth.txt when options.bag.groundtruth is given, and
// summary.json saying whether every frame was written. As `run` does: every option and the ground
// truth are checked before the first frame; a conversion stopped (a stop request, a frame that
// fails) leaves the frames before it with their lists, marked partial ("complete": false and the
// reason in summary.json); one that fails before its first frame leaves nothing.
#include <atomic>
#include <string>

#include "flowfusion/io/tum_sequence.h"

namespace ff {

struct BagConversion {
  size_t frames = 0;              // associated colour-depth pairs written
  size_t saturated_pixels = 0;    // depth beyond 65535 / 5000 = 13.1 m, written as 65535
  std::string color_topic, depth_topic;
  bool complete = true;           // false: `stop` ended it before the bag's end
  std::string stop_reason;        // *reason when stopped
};

// A non-empty `out_dir` is an InputError unless `overwrite` is set. `stop` is checked before each
// frame (a signal handler's flag); `reason` then says why. A frame that fails is an InputError
// that says the frames before it are kept as a partial result.
BagConversion convertBagToTum(const std::string& bag_path, const std::string& out_dir,
                              const SequenceOptions& options, bool overwrite = false,
                              const std::atomic<bool>* stop = nullptr, const char* const* reason = nullptr);

}  // namespace ff

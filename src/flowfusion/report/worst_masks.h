#pragma once
// The frames whose estimated dynamic masks score worst against the true ones, as a contact sheet
// (visualization/mask_sheet.h: colour, depth, true mask, estimate, both compared): what
// `flowfusion eval seg --sheet` writes, to see at a glance how the masks fail.
#include <opencv2/core.hpp>
#include <string>

#include "flowfusion/eval/segmentation_metrics.h"

namespace ff::report {

// Which frames are worst: the most pixels wrong (false positives and negatives: where the masks
// fail most), or the lowest IoU (what lowers the mean IoU most, often frames where the truth or
// the estimate is a sliver).
enum class WorstBy { kWrongPixels, kIou };

struct WorstMasksOptions {
  WorstBy by = WorstBy::kWrongPixels;
  int rows = 8;                 // frames shown, worst first (ties: earlier first)
  int column_width_px = 320;    // each image's width on the sheet
  double depth_scale = 5000.0;  // raw units per metre of the sequence's 16-bit depth PNGs (TUM: 5000)
};

// sequence_dir: the TUM-layout folder (rgb.txt, depth.txt) holding the masks' frames, read as
// stored: masks are in the stored images' pixels. Frames are found by the ground-truth masks'
// timestamps (colour within 0.02 s, depth nearest to it within 0.05 s); masks without a timestamp
// in their name are left out. Throws InputError naming the file when a list, a frame's image or
// the masks cannot be read or do not match, or when no frame has a timestamp.
cv::Mat worstMaskSheet(const std::string& sequence_dir, const eval::SegmentationResult& result,
                       const WorstMasksOptions& options = {});

}  // namespace ff::report

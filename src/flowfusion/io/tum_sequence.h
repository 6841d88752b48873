#pragma once
// RGB-D sequences in the TUM RGB-D benchmark layout: rgb.txt, depth.txt ("timestamp filename"
// lines, '#' comments), rgb/ and depth/ PNGs, optional groundtruth.txt, and optionally a
// camera.txt with the intrinsics and masks/<timestamp>.png with ground-truth dynamic masks
// (both written by `flowfusion synth` and `flowfusion augment`).
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/output_folder.h"  // prepareOutputDir, for the writers of sequences
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/undistortion.h"
#include "flowfusion/io/sequence_options.h"
#include "flowfusion/io/trajectory_io.h"

namespace ff {

// Raw 16-bit depth units per metre within what a depth sensor's images can mean (100: centimetres,
// 1000: millimetres, 5000: TUM, up to 65535, one metre at the 16-bit limit); InputError naming
// `name` (the option or argument) for a non-finite or absurd scale.
void checkDepthScale(double units_per_metre, const std::string& name);

struct FrameEntry {
  double rgb_timestamp = 0;    // s
  std::string rgb_path;        // absolute or relative to the working directory
  double depth_timestamp = 0;  // s
  std::string depth_path;
};

// One timestamped file list ("timestamp filename"). Throws InputError naming the file and line
// on malformed lines, unsorted or duplicate timestamps, or an empty list.
std::vector<std::pair<double, std::string>> readFileList(const std::string& path);

class TumSequence {
 public:
  // Reads the lists and resolves the camera: options.camera, else camera.txt in the folder, else
  // the dataset the folder's name and files identify (io/dataset_layout.h: TUM, Bonn, ICL-NUIM,
  // ETH3D). Throws InputError saying how to give intrinsics when none applies.
  static TumSequence open(const std::string& dir, const SequenceOptions& options = {});

  size_t size() const { return entries_.size(); }
  const FrameEntry& entry(size_t i) const { return entries_.at(i); }
  // Loads frame i and checks it: readable PNGs, 8-bit colour (3 channels; grey is expanded),
  // 16-bit single-channel depth, both of the camera's size. Undistorted when undistorter() is set.
  RgbdFrame load(size_t i) const;
  // The pinhole intrinsics of the frames load() returns.
  const CameraIntrinsics& camera() const { return camera_.intrinsics; }
  const LensDistortion& distortion() const { return camera_.distortion; }
  // Set when frames are undistorted on loading: takes per-frame outputs back to raw pixels.
  const Undistorter* undistorter() const { return undistorter_.get(); }
  // The same, shared with what outlives the sequence (a frame handed to Python).
  std::shared_ptr<const Undistorter> sharedUndistorter() const { return undistorter_; }
  const std::string& dir() const { return dir_; }
  const std::optional<Trajectory>& groundtruth() const { return groundtruth_; }
  // masks/ folder when the sequence carries ground-truth dynamic masks.
  std::optional<std::string> masksDir() const;

 private:
  std::string dir_;
  SequenceOptions options_;
  CameraModel camera_;
  std::shared_ptr<const Undistorter> undistorter_;
  std::vector<FrameEntry> entries_;
  std::optional<Trajectory> groundtruth_;
};

// camera.txt: one line "fx fy cx cy width height [k1 k2 p1 p2 k3]" ('#' comments), or a preset
// name fr1|fr2|fr3.
CameraModel readCameraFile(const std::string& path);
void writeCameraFile(const std::string& path, const CameraIntrinsics& camera);

// Writes a sequence in the TUM layout (used by synth and augment). Depth in metres is stored as
// 16-bit PNG at depth_scale units per metre; masks as 8-bit PNG (255 = dynamic).
class TumWriter {
 public:
  TumWriter(std::string dir, const CameraIntrinsics& camera, double depth_scale = 5000.0);
  // depth_timestamp: when the depth was taken, listed in depth.txt (NaN: with the colour, at
  // `timestamp`); the files are named after `timestamp` either way.
  void add(double timestamp, const cv::Mat& bgr8, const cv::Mat& depth_m, const SE3& T_world_cam,
           const cv::Mat& mask = {}, double depth_timestamp = std::numeric_limits<double>::quiet_NaN());
  // Writes rgb.txt, depth.txt, groundtruth.txt and camera.txt.
  void finish(const std::string& source_comment);

 private:
  std::string dir_;
  CameraIntrinsics camera_;
  double depth_scale_;
  std::vector<std::pair<double, std::string>> rgb_, depth_;
  Trajectory gt_;
  bool masks_ = false;
};

// "%.6f" of a timestamp, the file stem used for every per-frame file.
std::string timestampName(double t);

}  // namespace ff

#include "flowfusion/io/tum_sequence.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/io/dataset_layout.h"
#include "flowfusion/io/tum_text.h"

namespace fs = std::filesystem;

namespace ff {

std::string timestampName(double t) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6f", t);
  return buf;
}

std::vector<std::pair<double, std::string>> readFileList(const std::string& path) {
  RecordReader in(path, "file list", "timestamp filename");
  std::vector<std::pair<double, std::string>> out;
  while (in.next()) {
    const double t = in.timestamp();
    std::string file;
    if (!(in.fields() >> file)) in.malformed();
    out.emplace_back(t, file);
  }
  if (out.empty()) in.fail("file list is empty");
  return out;
}

CameraModel readCameraFile(const std::string& path) {
  RecordReader in(path, "camera file", "fx fy cx cy width height [k1 k2 p1 p2 k3]', or 'fr1|fr2|fr3");
  if (!in.next()) in.fail("camera file holds no intrinsics");
  std::string word;
  in.fields() >> word;
  if (word == "fr1" || word == "fr2" || word == "fr3") return parseCameraModel(word, path);
  std::istringstream nums(in.line());
  std::vector<double> v;
  for (double x; nums >> x;) v.push_back(x);
  if (!nums.eof() || (v.size() != 6 && v.size() != 11)) in.malformed();
  if (const auto problem = cameraValuesProblem(v)) in.fail(*problem);
  return cameraModelFromValues(v);
}

void writeCameraFile(const std::string& path, const CameraIntrinsics& c) {
  std::ostringstream out;
  out << "# fx fy cx cy width height (pixels)\n";
  out.precision(10);
  out << c.fx << ' ' << c.fy << ' ' << c.cx << ' ' << c.cy << ' ' << c.width << ' ' << c.height << '\n';
  writeFileAtomic(path, out.str(), "camera file");
}

void checkDepthScale(double units_per_metre, const std::string& name) {
  constexpr double kMin = 100, kMax = 65535;
  if (units_per_metre >= kMin && units_per_metre <= kMax) return;  // NaN fails both comparisons
  char given[32];
  std::snprintf(given, sizeof given, "%g", units_per_metre);
  throw InputError(name + ": " + given + " is not a finite number of raw depth units per metre in [100, 65535] " +
                   "(1000 = millimetres, 5000 = TUM)");
}

TumSequence TumSequence::open(const std::string& dir, const SequenceOptions& options) {
  if (!fs::is_directory(dir)) throw InputError(dir + ": sequence folder does not exist");
  TumSequence s;
  s.dir_ = dir;
  s.options_ = options;
  checkDepthScale(options.tum.depth_scale, "--depth-scale");

  const fs::path root(dir);
  if (!options.camera.empty()) {
    s.camera_ = parseCameraModel(options.camera);
  } else if (fs::exists(root / "camera.txt")) {
    s.camera_ = readCameraFile((root / "camera.txt").string());
  } else if (const auto dataset = detectDataset(dir)) {
    s.camera_ = dataset->camera;
  } else {
    throw InputError(dir + ": no camera intrinsics: " + datasetHelp());
  }

  if (options.undistort && !s.camera_.distortion.none())
    s.undistorter_ = std::make_shared<Undistorter>(s.camera_.intrinsics, s.camera_.distortion);

  const auto [rgb, depth] = readDatasetLists(dir);
  std::vector<double> ta, tb;
  for (const auto& e : rgb) ta.push_back(e.first);
  for (const auto& e : depth) tb.push_back(e.first);
  const auto pairs = associate(ta, tb, options.max_time_diff, StampLimit::kInclusive);
  if (pairs.empty())
    throw InputError(dir + ": no colour frame has a depth frame within " + std::to_string(options.max_time_diff) +
                     " s (check the timestamps in rgb.txt and depth.txt)");
  for (const auto& [i, j] : pairs)
    s.entries_.push_back({rgb[i].first, (root / rgb[i].second).string(), depth[j].first,
                          (root / depth[j].second).string()});
  if (const auto gt = datasetGroundtruthFile(dir)) s.groundtruth_ = readTrajectory(*gt);
  return s;
}

std::optional<std::string> TumSequence::masksDir() const {
  const fs::path p = fs::path(dir_) / "masks";
  if (fs::is_directory(p)) return p.string();
  return std::nullopt;
}

RgbdFrame TumSequence::load(size_t i) const {
  const FrameEntry& e = entries_.at(i);
  const cv::Size size(camera_.intrinsics.width, camera_.intrinsics.height);
  cv::Mat color = readImageFile(e.rgb_path, cv::IMREAD_UNCHANGED, "colour image", size);
  if (color.empty()) throw InputError(e.rgb_path + ": missing or unreadable colour image");
  if (color.depth() != CV_8U)
    throw InputError(e.rgb_path + ": colour image must be 8-bit per channel");
  if (color.channels() == 1) cv::cvtColor(color, color, cv::COLOR_GRAY2BGR);
  else if (color.channels() == 4) cv::cvtColor(color, color, cv::COLOR_BGRA2BGR);
  cv::Mat depth = readImageFile(e.depth_path, cv::IMREAD_UNCHANGED, "depth image", size);
  if (depth.empty()) throw InputError(e.depth_path + ": missing or unreadable depth image");
  if (depth.type() != CV_16UC1)
    throw InputError(e.depth_path + ": depth image must be 16-bit single-channel PNG (got " +
                     std::to_string(depth.elemSize1() * 8) + "-bit, " + std::to_string(depth.channels()) +
                     " channel(s))");
  const auto check = [&](const cv::Mat& m, const std::string& path) {
    const CameraIntrinsics& c = camera_.intrinsics;
    if (m.cols != c.width || m.rows != c.height)
      throw InputError(path + ": image is " + std::to_string(m.cols) + "x" + std::to_string(m.rows) +
                       ", the camera is " + std::to_string(c.width) + "x" + std::to_string(c.height));
  };
  check(color, e.rgb_path);
  check(depth, e.depth_path);
  if (undistorter_) {
    color = undistorter_->undistortColor(color);
    depth = undistorter_->undistortDepth(depth);
  }
  RgbdFrame frame = makeRgbdFrame(e.rgb_timestamp, color, depth, options_.tum.depth_scale, e.rgb_path);
  frame.depth_timestamp = e.depth_timestamp;
  return frame;
}

TumWriter::TumWriter(std::string dir, const CameraIntrinsics& camera, double depth_scale)
    : dir_(std::move(dir)), camera_(camera), depth_scale_(depth_scale) {
  fs::create_directories(fs::path(dir_) / "rgb");
  fs::create_directories(fs::path(dir_) / "depth");
}

void TumWriter::add(double timestamp, const cv::Mat& bgr8, const cv::Mat& depth_m, const SE3& T_world_cam,
                    const cv::Mat& mask, double depth_timestamp) {
  const std::string name = timestampName(timestamp) + ".png";
  const fs::path root(dir_);
  writePngAtomic((root / "rgb" / name).string(), bgr8, "colour image");
  cv::Mat d16;
  depth_m.convertTo(d16, CV_16U, depth_scale_);
  writePngAtomic((root / "depth" / name).string(), d16, "depth image");
  if (!mask.empty()) {
    if (!masks_) fs::create_directories(root / "masks");
    masks_ = true;
    writePngAtomic((root / "masks" / name).string(), mask, "mask");
  }
  rgb_.emplace_back(timestamp, "rgb/" + name);
  depth_.emplace_back(std::isnan(depth_timestamp) ? timestamp : depth_timestamp, "depth/" + name);
  gt_.push_back({timestamp, T_world_cam});
}

void TumWriter::finish(const std::string& source_comment) {
  const fs::path root(dir_);
  const auto writeList = [&](const std::string& file, const std::string& what,
                             const std::vector<std::pair<double, std::string>>& list) {
    std::ostringstream out;
    out << "# " << what << "\n# " << source_comment << "\n# timestamp filename\n";
    for (const auto& [t, f] : list) out << timestampName(t) << ' ' << f << '\n';
    writeFileAtomic((root / file).string(), out.str(), "file list");
  };
  writeList("rgb.txt", "color images", rgb_);
  writeList("depth.txt", "depth maps", depth_);
  writeTrajectory((root / "groundtruth.txt").string(), gt_);
  writeCameraFile((root / "camera.txt").string(), camera_);
}

}  // namespace ff

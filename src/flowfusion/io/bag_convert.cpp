#include "flowfusion/io/bag_convert.h"

#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <sstream>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/file_bytes.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/bag_reader.h"

namespace fs = std::filesystem;

namespace ff {

namespace {

constexpr double kTumDepthScale = 5000.0;  // raw units per metre in the written depth PNGs

// Depth in TUM's 16-bit units; counts the pixels too far for 16 bits.
cv::Mat tumDepth(const cv::Mat& depth, double depth_scale, size_t& saturated) {
  cv::Mat metres;
  if (depth.type() == CV_16UC1 && depth_scale == kTumDepthScale) return depth;
  depth.convertTo(metres, CV_64F, depth.type() == CV_16UC1 ? 1.0 / depth_scale : 1.0);
  saturated += static_cast<size_t>(cv::countNonZero(metres * kTumDepthScale > 65535.0));
  cv::Mat out;
  metres.convertTo(out, CV_16U, kTumDepthScale);
  return out;
}

// Enough digits that a nanosecond stamp reads back as the same double.
std::string stampText(double t) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.9f", t);
  return buf;
}

void writeList(const fs::path& file, const std::string& what, const std::string& source,
               const std::vector<std::pair<double, std::string>>& list) {
  std::ostringstream out;
  out << "# " << what << "\n# converted by flowfusion from " << source << "\n# timestamp filename\n";
  for (const auto& [t, f] : list) out << stampText(t) << ' ' << f << '\n';
  writeFileAtomic(file.string(), out.str(), "file list");
}

void writeCamera(const fs::path& file, const CameraModel& camera) {
  const CameraIntrinsics& c = camera.intrinsics;
  const LensDistortion& d = camera.distortion;
  std::ostringstream out;
  out.precision(12);
  out << "# fx fy cx cy width height" << (d.none() ? "" : " k1 k2 p1 p2 k3") << " (pixels)\n";
  out << c.fx << ' ' << c.fy << ' ' << c.cx << ' ' << c.cy << ' ' << c.width << ' ' << c.height;
  if (!d.none()) out << ' ' << d.k1 << ' ' << d.k2 << ' ' << d.p1 << ' ' << d.p2 << ' ' << d.k3;
  out << '\n';
  writeFileAtomic(file.string(), out.str(), "camera file");
}

// The ground truth to copy, read first so that a bad one is refused before any frame.
std::optional<std::string> groundtruthText(const std::string& path) {
  if (path.empty()) return std::nullopt;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError("--groundtruth " + path + ": no such file");
  readTrajectory(path);  // refuses a file that is not a TUM trajectory
  std::optional<std::string> text = readFileBytes(path);
  if (!text) throw InputError("--groundtruth " + path + ": cannot read it");
  return text;
}

// One frame's two images, their folders made on the first.
void writeFrame(const fs::path& root, const BagFrame& f, BagConversion& report,
                std::vector<std::pair<double, std::string>>& rgb, std::vector<std::pair<double, std::string>>& depth) {
  if (rgb.empty()) {
    fs::create_directories(root / "rgb");
    fs::create_directories(root / "depth");
  }
  const std::string color_file = "rgb/" + timestampName(f.timestamp) + ".png";
  const std::string depth_file = "depth/" + timestampName(f.depth_timestamp) + ".png";
  writePngAtomic((root / color_file).string(), f.bgr8, "colour image");
  writePngAtomic((root / depth_file).string(), tumDepth(f.depth, f.depth_scale, report.saturated_pixels),
                 "depth image");
  rgb.emplace_back(f.timestamp, color_file);
  depth.emplace_back(f.depth_timestamp, depth_file);
  ++report.frames;
}

void writeSummary(const fs::path& root, const std::string& bag_path, const BagConversion& report) {
  nlohmann::json j;
  j["command"] = "convert";
  j["bag"] = bag_path;
  j["complete"] = report.complete;
  if (!report.complete) j["stop_reason"] = report.stop_reason;
  j["frames"] = report.frames;
  j["color_topic"] = report.color_topic;
  j["depth_topic"] = report.depth_topic;
  j["saturated_depth_pixels"] = report.saturated_pixels;
  writeJsonFile((root / "summary.json").string(), j);
}

}  // namespace

BagConversion convertBagToTum(const std::string& bag_path, const std::string& out_dir,
                              const SequenceOptions& options, bool overwrite, const std::atomic<bool>* stop,
                              const char* const* reason) {
  const std::optional<std::string> groundtruth = groundtruthText(options.bag.groundtruth);
  BagReader reader = BagReader::open(bag_path, options);
  prepareOutputDir(out_dir, overwrite);
  const fs::path root(out_dir);
  BagConversion report{0, 0, reader.colorTopic(), reader.depthTopic()};
  std::vector<std::pair<double, std::string>> rgb, depth;
  std::exception_ptr failure;
  for (size_t i = 0; i < reader.size() && !failure; ++i) {
    if (stop && stop->load()) {
      report.complete = false;
      report.stop_reason = reason && *reason ? *reason : "stopped";
      break;
    }
    try {
      writeFrame(root, reader.read(i), report, rgb, depth);
    } catch (const std::exception& e) {
      if (report.frames == 0) {  // nothing worth keeping, and nothing left to block a rerun
        std::error_code ec;
        for (const char* folder : {"rgb", "depth"}) fs::remove(root / folder, ec);  // only when empty
        abandonOutputDir();
        throw;
      }
      report.complete = false;
      report.stop_reason = e.what();
      failure = std::current_exception();
    }
  }
  writeList(root / "rgb.txt", "color images", bag_path + " " + reader.colorTopic(), rgb);
  writeList(root / "depth.txt", "depth maps", bag_path + " " + reader.depthTopic(), depth);
  writeCamera(root / "camera.txt", reader.camera());
  if (groundtruth) writeFileAtomic((root / "groundtruth.txt").string(), *groundtruth, "groundtruth.txt");
  writeSummary(root, bag_path, report);
  if (!failure) return report;
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + "; the " + std::to_string(report.frames) + " frames before it are in " +
                     out_dir + ", marked partial in its summary.json");
  }
}

}  // namespace ff

#include "flowfusion/io/dataset_layout.h"

#include <algorithm>
#include <filesystem>
#include <regex>
#include <sstream>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/io/tum_sequence.h"
#include "flowfusion/io/tum_text.h"

namespace fs = std::filesystem;

namespace ff {

namespace {

// Published calibrations (pixels). Bonn: the dataset page's colour camera with its plumb-bob
// coefficients. ICL-NUIM: the dataset gives fy = -480 because its renderer's y axis points up;
// the PNGs are stored upright, so a pinhole camera with fy = +480 sees them as they are.
// ETH3D SLAM: calibration.txt in each sequence, images of 739x458.
CameraModel bonnCamera() {
  return cameraModelFromValues(
      {542.822841, 542.576870, 315.593520, 237.756098, 640, 480, 0.039903, -0.099343, -0.000730, -0.000144, 0.0});
}
CameraModel iclCamera() { return cameraModelFromValues({481.20, 480.00, 319.50, 239.50, 640, 480}); }
constexpr int kEth3dWidth = 739, kEth3dHeight = 458;

std::string folderName(const std::string& dir) { return fs::weakly_canonical(fs::path(dir)).filename().string(); }

// ICL-NUIM's trajectories (*.gt.freiburg) in the folder, sorted.
std::vector<std::string> iclGroundtruthFiles(const std::string& dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.path().filename().string().ends_with(".gt.freiburg")) found.push_back(e.path().string());
  std::sort(found.begin(), found.end());
  return found;
}

bool isIclFolder(const std::string& dir) {
  const fs::path root(dir);
  if (std::regex_search(folderName(dir), std::regex("^((living_?room|office_?room)_?)?traj[0-3]|^(lr|of)_?kt[0-3]",
                                                    std::regex::icase)))
    return true;
  return !iclGroundtruthFiles(dir).empty() ||
         (fs::exists(root / "associations.txt") && !fs::exists(root / "rgb.txt") && fs::is_directory(root / "rgb") &&
          fs::is_directory(root / "depth"));
}

DatasetCamera eth3dCamera(const std::string& dir) {
  const std::string path = (fs::path(dir) / "calibration.txt").string();
  RecordReader in(path, "ETH3D calibration file", "fx fy cx cy");
  if (!in.next()) in.fail("calibration file holds no intrinsics");
  std::istringstream nums(in.line());
  std::vector<double> v;
  for (double x; nums >> x;) v.push_back(x);
  if (!nums.eof() || v.size() != 4) in.malformed();
  cv::Size size(kEth3dWidth, kEth3dHeight);
  if (fs::exists(fs::path(dir) / "rgb.txt") || fs::exists(fs::path(dir) / "associations.txt")) {
    const auto rgb = readDatasetLists(dir).rgb;
    if (const auto s = readPngSize((fs::path(dir) / rgb.front().second).string())) size = *s;
  }
  v.push_back(size.width);
  v.push_back(size.height);
  if (const auto problem = cameraValuesProblem(v)) in.fail(*problem);
  return {Dataset::kEth3d, "ETH3D SLAM", cameraModelFromValues(v), 5000, path};
}

}  // namespace

std::optional<DatasetCamera> datasetCameraFromName(const std::string& name) {
  std::smatch m;
  if (std::regex_search(name, m, std::regex("^(rgbd_dataset_freiburg|fr)([123])_")))
    return DatasetCamera{Dataset::kTum, "TUM RGB-D fr" + m[2].str(), parseCameraModel("fr" + m[2].str()), 5000, name};
  if (std::regex_search(name, std::regex("^rgbd_bonn_")))
    return DatasetCamera{Dataset::kBonn, "Bonn RGB-D Dynamic", bonnCamera(), 5000, name};
  return std::nullopt;
}

std::optional<DatasetCamera> detectDataset(const std::string& dir) {
  if (auto named = datasetCameraFromName(folderName(dir))) return named;
  if (fs::exists(fs::path(dir) / "calibration.txt")) return eth3dCamera(dir);
  if (isIclFolder(dir)) return DatasetCamera{Dataset::kIclNuim, "ICL-NUIM", iclCamera(), 5000, folderName(dir)};
  return std::nullopt;
}

std::string datasetHelp() {
  return "give --camera fr1|fr2|fr3|fx,fy,cx,cy[,width,height], put a camera.txt ('fx fy cx cy width height') in "
         "the folder, or keep a dataset's own layout: a folder named rgbd_dataset_freiburgN_* or frN_* (TUM RGB-D), "
         "rgbd_bonn_* (Bonn RGB-D Dynamic), an ETH3D SLAM folder with calibration.txt, or an ICL-NUIM folder "
         "(associations.txt with rgb/ and depth/, or a *.gt.freiburg trajectory)";
}

FileLists readDatasetLists(const std::string& dir) {
  const fs::path root(dir);
  FileLists lists;
  if (fs::exists(root / "rgb.txt") || !fs::exists(root / "associations.txt")) {
    if (!fs::exists(root / "rgb.txt") && !fs::exists(root / "depth.txt"))
      throw InputError(dir + ": no frame lists: expected rgb.txt and depth.txt (TUM layout) or associations.txt "
                             "(ICL-NUIM)");
    lists.rgb = readFileList((root / "rgb.txt").string());
    lists.depth = readFileList((root / "depth.txt").string());
    return lists;
  }
  const std::string path = (root / "associations.txt").string();
  RecordReader in(path, "association file", "timestamp depth/file timestamp rgb/file");
  while (in.next()) {
    const double t1 = in.timestamp();
    std::string f1, f2;
    double t2;
    if (!(in.fields() >> f1 >> t2 >> f2)) in.malformed();
    const bool depth_first = f1.rfind("depth", 0) == 0;
    if (depth_first == (f2.rfind("depth", 0) == 0)) in.malformed();
    lists.depth.emplace_back(depth_first ? t1 : t2, depth_first ? f1 : f2);
    lists.rgb.emplace_back(depth_first ? t2 : t1, depth_first ? f2 : f1);
  }
  if (lists.rgb.empty()) in.fail("association file is empty");
  return lists;
}

std::optional<std::string> datasetGroundtruthFile(const std::string& dir) {
  const fs::path gt = fs::path(dir) / "groundtruth.txt";
  if (fs::exists(gt)) return gt.string();
  const std::vector<std::string> icl = iclGroundtruthFiles(dir);
  if (icl.size() > 1)
    throw InputError(dir + ": " + std::to_string(icl.size()) + " ground-truth trajectories (" + icl[0] + ", " + icl[1] +
                     (icl.size() > 2 ? ", ..." : "") + "); keep one *.gt.freiburg or copy the right one to groundtruth.txt");
  if (icl.empty()) return std::nullopt;
  return icl.front();
}

}  // namespace ff

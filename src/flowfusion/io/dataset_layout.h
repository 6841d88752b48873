#pragma once
// The RGB-D datasets of the dynamic-SLAM literature, recognised by their folder (or bag) names and
// contents so that their sequences run as downloaded: TUM RGB-D fr1/fr2/fr3, Bonn RGB-D Dynamic,
// ICL-NUIM in its TUM-compatible form and ETH3D SLAM. Each brings its camera and depth scale;
// --camera or a camera.txt overrides the camera (io/tum_sequence.h).
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "flowfusion/core/camera.h"

namespace ff {

enum class Dataset { kTum, kBonn, kIclNuim, kEth3d };

struct DatasetCamera {
  Dataset dataset = Dataset::kTum;
  std::string name;           // "TUM RGB-D fr1", "Bonn RGB-D Dynamic", "ICL-NUIM", "ETH3D SLAM"
  CameraModel camera;         // as the pipeline uses it (pinhole, positive focal lengths)
  double depth_scale = 5000;  // raw 16-bit depth units per metre
  std::string evidence;       // the name or file that identified it, for messages
};

// By a sequence's name alone (a folder's or a bag's, without extension): rgbd_dataset_freiburgN_*
// or frN_* (TUM), rgbd_bonn_* (Bonn). nullopt otherwise.
std::optional<DatasetCamera> datasetCameraFromName(const std::string& name);

// By a folder's name and contents: the names above; ICL-NUIM's TUM-compatible folders
// (associations.txt with rgb/ and depth/, a *.gt.freiburg trajectory, or a name
// living_room_traj*, office_room_traj*, traj*_frei_png); ETH3D SLAM (calibration.txt "fx fy cx
// cy", the size from the first colour image of rgb.txt or associations.txt). Throws InputError on an unreadable calibration.txt.
std::optional<DatasetCamera> detectDataset(const std::string& dir);

// What detectDataset looks for and how else to give the camera, for the error when none applies.
std::string datasetHelp();

// A folder's colour and depth file lists ("timestamp path" relative to the folder): rgb.txt and
// depth.txt, or else ICL-NUIM's associations.txt ("t depth/N.png t rgb/N.png" in either order).
// Throws InputError naming the file on malformed lines and saying which files were looked for
// when there are none.
struct FileLists {
  std::vector<std::pair<double, std::string>> rgb, depth;
};
FileLists readDatasetLists(const std::string& dir);

// The folder's ground-truth trajectory file: groundtruth.txt, or ICL-NUIM's single *.gt.freiburg
// (InputError naming them when there are several and no groundtruth.txt says which).
std::optional<std::string> datasetGroundtruthFile(const std::string& dir);

}  // namespace ff

#pragma once
// Pictures of the static map a person can open: shaded renderings from a few viewpoints.
#include <string>
#include <vector>

#include "flowfusion/fusion/static_map.h"

namespace ff {

// Shaded view of the map (surfel colours times a headlight Lambert term) at T_world_cam; background
// black. CV_8UC3 BGR of the camera's size.
cv::Mat renderPreview(const StaticMap& map, const SE3& T_world_cam, const CameraIntrinsics& camera);
// Writes preview_<i>.png into `dir` (created if needed) from a few viewpoints around the map: the
// first keyframe and views orbiting the map's centre. Returns the paths written.
std::vector<std::string> writePreviews(const StaticMap& map, const std::string& dir);

}  // namespace ff

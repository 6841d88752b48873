#pragma once
// A run's map for the next run to continue in (`run --map-in`): the stable surfels of the static
// map, the loop closer's keyframes (pose after the last loop closure and the images the place
// index and the geometric check need) and the camera, in one versioned binary file, map.ffmap
// (layout in docs/formats.md). The ferns' codes are not stored: the reading run encodes the small
// images with its own index, so only the images' level and size have to agree.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/fusion/static_map.h"
#include "flowfusion/slam/keyframe.h"
#include "flowfusion/slam/slam_config.h"

namespace ff {

inline constexpr const char* kMapFileName = "map.ffmap";
inline constexpr uint32_t kMapFileVersion = 1;

struct SavedMap {
  std::string path;          // where it was read from (empty when made in memory)
  CameraIntrinsics camera;   // the run's pinhole camera at the input size
  int keyframe_level = 1;    // slam.keyframe_level of the keyframes' images
  int fern_image_width = 80; // slam.fern_image_width of their small images
  // Position, normal, radius, confidence, colour and intensity are kept; a reading run takes the
  // surfels as made before it (StaticMap::loadSurfels).
  std::vector<Surfel> surfels;
  std::vector<SavedKeyframe> keyframes;
};

// The map of a finished run: the stable surfels of `map` (none when null) and the keyframes.
SavedMap savedMap(const StaticMap* map, std::vector<SavedKeyframe> keyframes, const CameraIntrinsics& camera,
                  const SlamConfig& slam);

// Writes `map` to `path` atomically (core/atomic_file.h). Images are lossless PNG, the rest raw.
void writeMapFile(const std::string& path, const SavedMap& map);

// Reads a map file: an InputError naming the file and the reason when it is missing, not a map
// file, of another version, truncated or corrupt (checksum), or inconsistent.
SavedMap readMapFile(const std::string& path);

// `path` itself when it is a file, else the map file inside the run folder `path`.
std::string mapFileIn(const std::string& path);

// InputError naming the map's file when a run with `camera` and `slam` cannot continue in it:
// another camera (intrinsics or image size), other keyframe images (slam.keyframe_level,
// slam.fern_image_width), no keyframes to localize against.
void checkMapFits(const SavedMap& map, const CameraIntrinsics& camera, const SlamConfig& slam);

// What `run --map-in MAP_IN` continues in: mapFileIn(map_in) read and checked for a run with
// `camera` and `slam` (checkMapFits; loop closure on, in a build that has it). The output folder
// `out_dir` (empty: none) may not be, contain or lie inside map_in: the run never touches it.
SavedMap readMapFor(const std::string& map_in, const std::string& out_dir, const CameraIntrinsics& camera,
                    const SlamConfig& slam);

}  // namespace ff

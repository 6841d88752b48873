#pragma once
// How a recording is read (`run`, `bench`, `convert`, the Python package): what every reader takes
// (the camera, undistortion, the colour-depth association), then the options of TUM-layout folders
// (io/tum_sequence.h) and of ROS bags (io/bag_source.h) apart.
#include <string>

namespace ff {

// A TUM-layout folder's options.
struct TumOptions {
  double depth_scale = 5000.0;  // raw depth units per metre of the 16-bit PNGs (TUM: 5000)
};

// A ROS bag's options.
struct BagOptions {
  std::string rgb_topic, depth_topic;  // "" = found by name
  double depth_scale = 1000.0;         // raw 16UC1 depth units per metre (ROS drivers: millimetres)
  std::string groundtruth;             // a TUM groundtruth.txt for the recording ("" = none)
};

struct SequenceOptions {
  double max_time_diff = 0.02;  // s, colour-depth association limit (as the benchmark's associate.py)
  std::string camera;           // "", "fr1|fr2|fr3" or "fx,fy,cx,cy[...]": overrides detection
  // Undistort frames as they are loaded when the camera has lens distortion (fr1, fr2 or
  // coefficients in the spec or camera.txt); false feeds the raw images to the pinhole model.
  bool undistort = true;
  TumOptions tum;
  BagOptions bag;
};

}  // namespace ff

#pragma once
// Dense map of the static background: a surfel map in the style of ElasticFusion / StaticFusion,
// fed per pixel with the static weight (1 - b) of the segmentation, rendered for frame-to-model
// tracking, exported as PLY.
//
// Why surfels and not a TSDF: on the CPU, Open3D's TSDF (the one Debian ships) takes as long to
// integrate a frame at 2 cm voxels as this map takes to integrate and render it, and has no ray
// caster for the prediction; splatted discs reproduce planes exactly (docs/tuning.md#fusion).
// Ghost removal is natural with surfels: each frame, every surfel that projects in front of the
// measured depth (the camera sees through it) gets a free-space vote, and one at the depth of a
// pixel weighted as dynamic a dynamic vote; a surfel with more votes than support is removed.
// Surfels that never become stable (confidence below stable_confidence within
// unstable_window_frames) are removed too. A background that was occluded gets new surfels as
// soon as it is seen with weight.
// A triangle mesh is made at export time from the stable surfels alone (surfel_mesh.h: their planes
// through a sparse TSDF, then marching cubes), so it holds only the static surfaces.
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"

namespace ff {

struct FusionConfig {
  // Input pixels fused per frame: every stride-th pixel in x and y (2: 640x480 is fused at 320x240).
  int integration_stride = 2;
  // Depth range fused, metres along the optical axis.
  double min_depth_m = 0.2;
  double max_depth_m = 4.0;
  // Pixels with static weight (1 - b) below this are not fused (treated as dynamic).
  double min_static_weight = 0.1;
  // A measurement updates the surfel at its pixel when their depths differ by less than
  // association_distance_m * max(1, depth in metres) and their normals by less than
  // association_angle_deg.
  double association_distance_m = 0.02;
  double association_angle_deg = 30.0;
  // Neighbouring depths that differ by more than this fraction of the depth are a discontinuity:
  // no normal, no surfel there.
  double depth_discontinuity_ratio = 0.05;
  // Surfel radius = radius_scale * pixel footprint at the fused resolution / max(cos(view angle), 0.3).
  double radius_scale = 0.8;
  // A surfel is stable once its summed weight reaches this; unstable surfels older than
  // unstable_window_frames are removed (noise and transient objects never get stable).
  double stable_confidence = 2.0;
  int unstable_window_frames = 20;
  // Free space: a surfel that projects in front of the measured depth (minimum over its 3x3
  // neighbourhood at the fused resolution) by more than free_space_margin_m * max(1, depth) gets a
  // vote; each association takes one away; free_space_votes votes remove it.
  double free_space_margin_m = 0.05;
  int free_space_votes = 2;
  // A surfel at the depth of a pixel weighted as dynamic (below min_static_weight) gets a vote too:
  // an object fused while it stood still, or before it was detected, leaves the map once it is
  // seen moving, instead of becoming background that the segmentation then agrees with.
  bool dynamic_removal = true;
  // Memory budget: at most this many surfels (about 64 bytes each). When reached no new surfels
  // are added (existing ones still update), budgetReached() turns true and one warning is logged.
  int max_surfels = 3000000;
  // A new keyframe pose (used for the previews) is stored when the camera moved this far from
  // the last one; at most max_keyframes are kept (evenly thinned beyond that).
  double keyframe_distance_m = 0.1;
  double keyframe_angle_deg = 10.0;
  int max_keyframes = 60;
  // Mesh export: voxel size of the surfels' TSDF, and the bound on its signed distances, metres.
  double mesh_voxel_m = 0.01;
  double mesh_truncation_m = 0.04;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(FusionConfig, integration_stride, min_depth_m, max_depth_m,
                                                min_static_weight, association_distance_m, association_angle_deg,
                                                depth_discontinuity_ratio, radius_scale, stable_confidence,
                                                unstable_window_frames, free_space_margin_m, free_space_votes, dynamic_removal,
                                                max_surfels, keyframe_distance_m, keyframe_angle_deg, max_keyframes,
                                                mesh_voxel_m, mesh_truncation_m)

// Throws InputError naming the setting when a value is out of range.
void validate(const FusionConfig& config);

// The model seen from one camera. Pixels the model does not cover hold 0 in every image.
struct ModelPrediction {
  cv::Mat depth;      // CV_32FC1, metres along the optical axis, 0 = none
  cv::Mat intensity;  // CV_32FC1 in [0, 1]
  cv::Mat color;      // CV_8UC3, BGR
  cv::Mat normal;     // CV_32FC3, unit normals in the camera frame (facing the camera), 0 = none
};

// Map points for evaluation and export (world frame).
struct MapPoints {
  std::vector<Eigen::Vector3f> positions;  // metres
  std::vector<Eigen::Vector3f> normals;    // unit
  std::vector<cv::Vec3b> colors;           // BGR
};

struct Surfel {
  Eigen::Vector3f position;  // world, metres
  Eigen::Vector3f normal;    // world, unit
  float radius = 0;          // metres
  float confidence = 0;      // summed static weight of the fused measurements
  float bgr[3] = {0, 0, 0};  // 0..255
  float intensity = 0;       // [0, 1]
  int32_t created = 0;       // frame index of creation
  int32_t last_seen = 0;     // frame index of the last update
  int32_t removal_votes = 0;  // free-space and dynamic votes minus associations
};

class StaticMap {
 public:
  explicit StaticMap(const FusionConfig& config = {});

  // Fuses one frame seen at T_world_cam. static_weight: CV_32FC1 in [0, 1] per pixel (1 - b, 0 =
  // dynamic), the frame's size, or empty for all static. Throws InputError on mismatched sizes or
  // types.
  void integrate(const RgbdFrame& frame, const CameraIntrinsics& camera, const SE3& T_world_cam,
                 const cv::Mat& static_weight = {});

  // Renders the model at T_world_cam with `camera` (any resolution): colour, intensity and normal
  // of the nearest surfel whose disc the pixel's ray meets, depth the confidence-weighted mean of
  // the discs it meets near that front surface (two passes; one alone is biased towards the camera
  // by the noise). Unstable surfels observed in the last frame are drawn too (tracking wants every
  // surface it just saw).
  ModelPrediction predict(const SE3& T_world_cam, const CameraIntrinsics& camera) const;

  // predict()'s depth alone for tracking targets, each surfel splatted as a small square inside its
  // disc's image with its plane's depth instead of as a ray-traced disc: well under half predict()'s
  // time and no less accurate for tracking (see kInnerSquare; docs/tuning.md#predict_depth). Pixels
  // between the squares may stay empty (0).
  cv::Mat predictDepth(const SE3& T_world_cam, const CameraIntrinsics& camera) const;

  // Depth (CV_32FC1, metres, 0 = none) of the stable surfels only, each splatted as a square of its
  // projected diameter with its plane's depth: what the segmentation compares a frame against (a
  // moving object fused once by mistake is not yet part of the background). The square covers a
  // little more than the disc (depth edges bleed by a pixel towards the far side, which only hides
  // evidence), and without predict()'s per-surfel ellipse bound and ray-disc test it costs about
  // half as much. `intensity`, when given, receives the front surfel's intensity per pixel
  // (CV_32FC1 in [0, 1], 0 = none).
  cv::Mat predictStableDepth(const SE3& T_world_cam, const CameraIntrinsics& camera, cv::Mat* intensity = nullptr) const;

  // Moves each surfel (position and normal) by T_new_old_by_integration[its creating integration,
  // Surfel::created]: a loop closure's correction of the keyframe each was fused near. Surfels of
  // later integrations than the list holds stay. One pass over the surfels (static_map_correction.cpp).
  void moveSurfels(const std::vector<SE3>& T_new_old_by_integration);

  // Before the first integrate(): the surfels of a saved map (slam/map_file.h) this run continues
  // in, kept as they were (geometry, colour, confidence) and taken as made before this run
  // (Surfel::created and last_seen -1, no votes): they stay when a loop closure of this run moves
  // its own surfels, and leave only by the free-space and dynamic votes. Up to max_surfels.
  void loadSurfels(const std::vector<Surfel>& surfels);

  size_t size() const { return surfels_.size(); }
  bool budgetReached() const { return budget_reached_; }
  const std::vector<Surfel>& surfels() const { return surfels_; }
  const FusionConfig& config() const { return config_; }
  // Camera poses kept for the previews.
  const std::vector<SE3>& keyframePoses() const { return keyframes_; }
  // The camera of the last integrated frame.
  const CameraIntrinsics& keyframeCamera() const { return keyframe_camera_; }

  // Stable surfels only (what the exports hold).
  MapPoints points() const;
  // Whether any surfel is stable (what the exports need), without copying them.
  bool hasStableSurfels() const;

  // Coloured point cloud with normals (binary PLY). Throws InputError if the file cannot be written.
  void exportPointCloud(const std::string& path) const;
  // Triangle mesh with vertex colours (binary PLY). Throws InputError if the file cannot be written.
  void exportMesh(const std::string& path) const;

 private:
  void updateKeyframes(const SE3& T_world_cam, const CameraIntrinsics& camera);

  FusionConfig config_;
  std::vector<Surfel> surfels_;
  std::vector<SE3> keyframes_;
  CameraIntrinsics keyframe_camera_;
  int frame_index_ = 0;
  bool budget_reached_ = false;
};

}  // namespace ff

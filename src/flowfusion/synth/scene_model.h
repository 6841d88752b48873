#pragma once
// Internal: the geometry, textures and motion of a synthetic scene and the ray caster shared by
// `synth` (a whole room) and `augment` (moving objects only, composited into real frames).
#include <Eigen/Core>
#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/synth/texture.h"

namespace ff::synth {

nlohmann::json jsonVec(const Eigen::Vector3d& v);

// An axis-aligned box in its owner's frame (world for furniture, object frame for moving objects).
struct Part {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // m
  int texture = 0;                                     // index into SceneModel::textures
  Eigen::Vector2d offset_m = Eigen::Vector2d::Zero();  // texture offset, so equal materials differ
  float albedo = 1.0f;                                 // brightness factor of the texture
};

// A group of parts with their common bounds (culls rays that miss the whole group).
struct Item {
  std::string kind;
  std::vector<Part> parts;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  void add(const Part& p);
  nlohmann::json describe() const;
};

// A smooth function of time: sum of sinusoids a sin(w t + phi).
struct Sinusoids {
  std::vector<std::array<double, 3>> terms;  // amplitude, angular frequency (rad/s), phase (rad)
  double value(double t) const;
  double derivative(double t) const;
  double rmsDerivative() const;  // long-run RMS of the derivative
  void scaleTime(double k);      // f(t) -> f(k t)
  nlohmann::json describe() const;
};

class ObjectPath {
 public:
  virtual ~ObjectPath() = default;
  virtual SE3 T_world_object(double t) const = 0;  // t: seconds since the sequence start
  virtual nlohmann::json describe() const = 0;
};

// Laid out in the frame of a camera at time 0 (cam0): starts in front of it and oscillates mostly
// sideways (so it crosses the view), tumbling about its own axis.
class CameraRelativePath : public ObjectPath {
 public:
  SE3 T_world_cam0 = SE3::Identity();
  Eigen::Vector3d p0_cam0 = Eigen::Vector3d::Zero();  // m
  std::array<Sinusoids, 3> offset;                     // cam0 x, y, z offsets, m
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();    // initial orientation in cam0
  Eigen::Vector3d spin_axis = Eigen::Vector3d::UnitY();
  Sinusoids spin;  // rad

  SE3 T_world_object(double t) const override;
  double rmsSpeed() const;  // m/s
  nlohmann::json describe() const override;
};

// A random crossing path at a distance in [min_distance, max_distance] (m) in front of cam0, whose
// view spans tan_x, tan_y (half-width and half-height over the focal length), RMS speed speed_mps.
std::shared_ptr<CameraRelativePath> crossingPath(Rng& rng, const SE3& T_world_cam0, double tan_x, double tan_y,
                                                 double min_distance, double max_distance, double speed_mps);

struct MovingObject {
  Item shape;  // parts in the object frame
  std::shared_ptr<const ObjectPath> path;
};

// The room: the inside of the box [0, size], one texture per face (-x, +x, -y, +y, floor, ceiling).
struct Room {
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  std::array<Part, 6> faces;
};

// View-independent lighting (Lambert, point light with distance falloff, plus ambient), so that a
// static surface point has the same colour in every frame.
struct Light {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, m
  double ambient = 0.35, diffuse = 0.9;
  double falloff_m = 3.0;  // distance at which the diffuse term halves
};

struct RenderOptions {
  CameraIntrinsics camera;
  bool noise = true;
  double min_depth = 0.4, max_depth = 6.0;  // m
  double color_noise = 1.5;                 // 8-bit levels
  bool depth_shadows = true;                // Kinect-like holes on the far side of depth edges
  double psf_sigma_px = 0.5;                // camera blur, pixels (also removes geometric aliasing)
  uint64_t noise_key = 0;                   // per-frame key of the counter-based noise
};

struct RenderedLayer {
  cv::Mat color;        // CV_32FC3 BGR in [0, 1] (noise-free, before blur), black where nothing is hit
  cv::Mat depth_clean;  // CV_32F, m, 0 = nothing hit
  cv::Mat object_id;    // CV_8U, 0 = static, k + 1 = moving object k
  cv::Mat cos_incidence;  // CV_32F, |cos| of the angle between the ray and the surface normal
};

// Hand-held camera: position and yaw/pitch/roll are sums of a few sinusoids around a centre; time
// is scaled so that the RMS speeds match the configuration. A loop (loop_rate != 0) also carries
// the centre round a circle of loop_radius_m, the camera looking outwards from it.
struct CameraPath {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double yaw0 = 0, pitch0 = 0;
  double loop_radius_m = 0;
  double loop_rate = 0;  // rad/s round the circle (0: no loop)
  std::array<Sinusoids, 3> position;  // x, y, z offsets, m
  Sinusoids yaw, pitch, roll;         // rad
  double start_s = 0;                 // the sequence starts this far along the path, s

  SE3 T_world_cam(double t) const;  // t: seconds since the sequence start

  nlohmann::json describe() const;
};

class SceneModel {
 public:
  std::optional<Room> room;
  std::vector<Item> furniture;  // world frame
  std::vector<MovingObject> objects;
  std::vector<Texture> textures;
  std::vector<std::string> texture_names;
  Light light;

  int addTexture(Material m, Rng& rng);
  RenderedLayer cast(const SE3& T_world_cam, double time_s, const CameraIntrinsics& camera) const;
};

// Sinusoids with the given (amplitude, frequency in Hz) terms, amplitudes and frequencies jittered
// by +-30% and +-25%, random phases.
Sinusoids randomSinusoids(Rng& rng, const std::vector<std::pair<double, double>>& amp_freq_hz);
Part box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int texture, Rng& rng, float albedo = 1.0f);
// Upright person-sized shape (legs, torso, arms, head; about 0.6 x 0.35 x 1.75 m), object frame:
// origin on the floor, x forward, z up. Adds its clothing and skin textures to m.
Item personShape(SceneModel& m, Rng& rng);
// The same shape with its bounds centred on the object frame's origin (for tumbling objects).
Item centred(Item shape);
// A textured box (cardboard or printed) with sides in [min_side, max_side] (height up to 1.3x),
// standing on the object frame's origin.
Item boxShape(SceneModel& m, Rng& rng, double min_side, double max_side);

// The camera image after the blur and colour noise (CV_8UC3).
cv::Mat finishColor(const cv::Mat& color_f, const RenderOptions& options);
// Kinect-like depth from clean depth: range limits, holes at depth edges and grazing angles,
// noise growing with range, disparity quantisation, then 1/5000 m quantisation (TUM PNG).
// Without options.noise the clean depth is returned unchanged.
cv::Mat kinectDepth(const cv::Mat& depth_clean, const cv::Mat& cos_incidence, const RenderOptions& options);

}  // namespace ff::synth

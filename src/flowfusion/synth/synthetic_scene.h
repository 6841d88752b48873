#pragma once
// Synthetic dynamic RGB-D scenes with exact ground truth (camera poses, depth, dynamic masks).
//
// A procedurally generated room (walls, floor, ceiling, furniture-sized boxes, pictures) textured
// with fractal 1/f noise, wood grain, blobs and edges, lit by a view-independent point light (so
// brightness constancy holds exactly for static surfaces), seen by a hand-held-like camera on a
// smooth trajectory, with K rigid moving objects (upright person-sized shapes and boxes), and, for the
// hard cases of real dynamic scenes, articulated people who walk, stop, turn, sit down and get up
// (people.h), fast camera rotation, motion blur, large movers near the camera and objects that rest
// and are then pushed.
// Everything is analytic ray casting: per pixel the nearest hit of planes and boxes.
//
// World frame: metres, z up, the room spans [0, W] x [0, D] x [0, H]. Camera frame: x right,
// y down, z forward (optical axis). Depth is z in the camera frame.
//
// Determinism: everything derives from the seed through mt19937_64 and hand-written
// distributions; per-pixel noise uses a counter-based hash of (seed, frame, pixel), so results do
// not depend on thread scheduling. The room and camera come from one random stream and the
// objects from another, so `objects = 0` gives the static twin of the same room and trajectory.
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/config_enum.h"
#include "flowfusion/core/rgbd_frame.h"
#include "flowfusion/core/se3.h"
#include "flowfusion/io/tum_sequence.h"

namespace ff::synth {

// How the camera moves: a hand-held sweep (mostly yaw, as TUM fr1/xyz, fr3 walking_xyz) or fast
// rotation about all three axes with little translation (as TUM fr1/rpy, fr3 walking_rpy).
enum class CameraMotion { Handheld, Rpy };

// Where the camera goes: the hand-held sweep about the room's centre, or a loop round a circle of
// kLoopRadiusM about it, looking outwards (to see the same places again: loop closure).
enum class CameraPathKind { Sweep, Loop };
inline constexpr double kLoopRadiusM = 0.6;

// What a hole in the real depth (a pixel the sensor returned nothing for) hides of a pasted object.
enum class HoleTest {
  // Only what lies behind valid depth enclosing the hole on both sides of its row or column within
  // a tenth of the image's width (generator version 2: a person showed through a black screen too
  // large for its speckles to enclose, or cut by the image's edge).
  Enclosed,
  // Besides, on black pixels (a black surface returns no depth), what lies behind the nearest surface
  // beside the hole along its row or column (generator version 3).
  BlackSurfaces,
};

// What a pasted object returns in the depth sensor's band, the lines at the image's edges where the
// real frame has no depth (SensorBand::of: the registered depth's border, on TUM fr1 about 45 rows at
// the top and 12 and 50 columns at the left and the right, a fifth of the image).
enum class BandDepth {
  // Its depth, as elsewhere (generator version 3; a Kinect's registered depth has none there).
  Drawn,
  // None: the object shows in the colour and the mask only, as it would to the real sensor
  // (generator version 4, the default).
  None,
};

}  // namespace ff::synth

namespace ff {
FLOWFUSION_CONFIG_ENUM_NAMES(synth::CameraMotion, "camera_motion", {synth::CameraMotion::Handheld, "handheld"},
                             {synth::CameraMotion::Rpy, "rpy"})
FLOWFUSION_CONFIG_ENUM_NAMES(synth::CameraPathKind, "camera_path", {synth::CameraPathKind::Sweep, "sweep"},
                             {synth::CameraPathKind::Loop, "loop"})
FLOWFUSION_CONFIG_ENUM_NAMES(synth::HoleTest, "holes", {synth::HoleTest::Enclosed, "enclosed"},
                             {synth::HoleTest::BlackSurfaces, "black_surfaces"})
FLOWFUSION_CONFIG_ENUM_NAMES(synth::BandDepth, "band_depth", {synth::BandDepth::Drawn, "drawn"},
                             {synth::BandDepth::None, "none"})
}  // namespace ff

namespace ff::synth {

FLOWFUSION_CONFIG_ENUM_JSON(CameraMotion)
FLOWFUSION_CONFIG_ENUM_JSON(CameraPathKind)
FLOWFUSION_CONFIG_ENUM_JSON(HoleTest)
FLOWFUSION_CONFIG_ENUM_JSON(BandDepth)

// Bumped whenever the same seed would produce different images; written to scene.json.
inline constexpr int kGeneratorVersion = 4;

struct SynthConfig {
  uint64_t seed = 1;        // selects room, trajectory, objects and noise
  int frames = 300;         // number of frames
  int objects = 2;          // number of moving objects (0: the static twin)
  int width = 640;          // image size, pixels; the fr1 intrinsics are scaled to it
  int height = 480;
  double fps = 30;          // frame rate, Hz
  double start_time = 1.0;  // timestamp of frame 0, s
  double camera_speed = 0.25;          // RMS translational speed of the camera, m/s (TUM: up to ~0.5)
  double camera_angular_speed = 15.0;  // RMS angular speed of the camera, deg/s (TUM: up to ~50)
  double object_speed = 0.5;           // RMS speed of the moving objects' centres, m/s
  bool noise = true;        // false: exact analytic depth with no holes and noise-free colour (for tests)
  double min_depth = 0.4;   // m, nearer surfaces have no depth (noise = true only)
  double max_depth = 6.0;   // m, farther surfaces have no depth (noise = true only)
  double color_noise = 1.5; // colour sensor noise sigma, 8-bit levels (noise = true only)
  // The hard cases of real dynamic scenes. At their defaults (0, handheld) a seed renders exactly as
  // before they existed; each draws from its own random stream, so they do not change each other.
  int people = 0;           // articulated people walking across the first view (12 moving objects each)
  int seats = 0;            // seats (static boxes) in the first view; person k < seats sits on seat k
  int near_objects = 0;     // large boxes (0.45-0.65 m) 1.0-1.5 m in front of the first camera, crossing it
  int pushed_objects = 0;   // chairs and boxes in view that rest, are pushed, rest, are pushed back
  double rest_s = 3.0;      // s, how long pushed objects rest before each push
  CameraMotion camera_motion = CameraMotion::Handheld;
  // loop: round the room's centre at camera_speed with a hand-held wobble; the free-standing
  // furniture near the centre is left out (the camera would pass through it).
  CameraPathKind camera_path = CameraPathKind::Sweep;
  int laps = 0;  // with camera_path loop: > 0 sets frames to this many laps (0: frames decides)
  // A second recording of the same room (the room comes from seed alone; ground truth in the same
  // world frame), for map reuse: the camera path starts this many seconds along (people walk
  // across the view it starts at), and with camera_path loop its wobble is drawn from path_seed
  // (0: seed), so the path differs from the first recording's.
  double path_start_s = 0;
  uint64_t path_seed = 0;
  // A kidnap: the view covered (black, no depth, as a hand over the lens) for cover_s seconds from
  // cover_at_s after the start, while the camera goes on moving (0: never).
  double cover_at_s = 0;
  double cover_s = 0;
  double exposure_ms = 0;   // ms, motion blur: colour averaged over this exposure centred on the timestamp (0: off)
  int exposure_samples = 8; // sub-frame renders averaged when exposure_ms > 0
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(SynthConfig, seed, frames, objects, width, height, fps, start_time,
                                                camera_speed, camera_angular_speed, object_speed, noise, min_depth,
                                                max_depth, color_noise, people, seats, near_objects, pushed_objects,
                                                rest_s, camera_motion, camera_path, laps, path_start_s, path_seed,
                                                cover_at_s, cover_s,
                                                exposure_ms,
                                                exposure_samples)

// The frames a configuration renders: `frames`, or `laps` laps of a loop at camera_speed and fps.
int frameCount(const SynthConfig& config);

struct SynthFrame {
  RgbdFrame frame;        // colour, intensity, depth (metres, noisy and quantised to 1/5000 m unless noise = false)
  SE3 T_world_cam;        // exact
  cv::Mat mask;           // CV_8UC1, 255 where a moving object is visible, else 0 (at the timestamp, also with blur)
  cv::Mat object_id;      // CV_8UC1, 0 = static scene, k + 1 = moving object k (a person is 12 of them)
  cv::Mat depth_clean;    // CV_32FC1, exact depth of the visible surface, m (0 = none)
};

// Kinect-like depth noise: sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 metres (Nguyen et al. 2012).
double depthNoiseSigma(double z_m);

class SceneModel;  // geometry, textures and motion (scene_model.h)
class Body;        // an articulated person (body.h)
struct CameraPath;

class SyntheticScene {
 public:
  // Throws InputError on a nonsensical configuration (sizes, counts, rates).
  explicit SyntheticScene(const SynthConfig& config);
  ~SyntheticScene();
  SyntheticScene(SyntheticScene&&) noexcept;
  SyntheticScene& operator=(SyntheticScene&&) noexcept;

  const SynthConfig& config() const { return config_; }
  const CameraIntrinsics& camera() const { return camera_; }
  int frameCount() const { return config_.frames; }
  double timestamp(int i) const;   // s
  SE3 cameraPose(int i) const;     // T_world_cam at frame i
  SE3 cameraPoseAt(double time_s) const;
  int objectCount() const;
  SE3 objectPose(int k, double time_s) const;  // T_world_object of moving object k

  SynthFrame render(int i) const;  // thread-safe, deterministic; blank inside the cover window
  // Any pose; objects are placed at time_s (a timestamp on the same clock as timestamp(i)).
  // Noise is seeded by the time, so render(i) == renderAt(cameraPose(i), timestamp(i)) outside the
  // cover window.
  SynthFrame renderAt(const SE3& T_world_cam, double time_s) const;

  // The articulated people: person k is moving objects firstPersonObject() + 12 k ... + 12 k + 11,
  // in the order of BodyPart.
  int personCount() const { return static_cast<int>(people_.size()); }
  int firstPersonObject() const { return first_person_object_; }
  std::shared_ptr<const Body> person(int k) const;

  // scene.json content: seed, configuration, room, furniture, people, objects (sizes, paths), version.
  nlohmann::json description() const;

 private:
  cv::Mat exposureColor(const SE3& T_world_cam, double t) const;  // t: s since the sequence start

  SynthConfig config_;
  CameraIntrinsics camera_;
  std::unique_ptr<SceneModel> model_;
  std::shared_ptr<const CameraPath> camera_path_;
  std::vector<std::shared_ptr<const Body>> people_;
  int first_person_object_ = 0;
};

// Writes every frame in the TUM layout (rgb/, depth/, masks/, rgb.txt, depth.txt, groundtruth.txt,
// camera.txt) plus scene.json. A non-empty out_dir is an InputError unless overwrite is set.
void writeSequence(const SyntheticScene& scene, const std::string& out_dir, bool overwrite = false);

// Inserting moving objects into a real static sequence with ground-truth poses.
struct AugmentConfig {
  uint64_t seed = 1;           // selects objects, paths and noise
  int objects = 2;             // number of inserted boxes (objects + people >= 1)
  int first_frame = 0;         // first colour frame used (index into rgb.txt after association)
  int last_frame = -1;         // last colour frame used, inclusive (-1: the last one)
  double min_distance = 0.7;   // m, nearest initial object distance from the first camera
  double max_distance = 2.0;   // m, farthest initial object distance
  double object_speed = 0.4;   // RMS speed of the objects, m/s
  bool noise = true;           // Kinect-like noise and quantisation on the object depth
  double max_pose_gap = 0.1;   // s, largest ground-truth gap bridged by interpolation
  // Articulated people walking across the first camera's view, 1.0-1.6 m in front of it, on a floor
  // camera_height below the first camera (the world's z axis is taken as up, as in TUM's ground truth).
  int people = 0;
  double camera_height = 1.45;  // m, height of the first camera above the floor
  HoleTest holes = HoleTest::BlackSurfaces;
  BandDepth band_depth = BandDepth::None;
};
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(AugmentConfig, seed, objects, first_frame, last_frame, min_distance,
                                                max_distance, object_speed, noise, max_pose_gap, people, camera_height,
                                                holes, band_depth)

struct AugmentReport {
  int frames_written = 0;
  std::vector<double> dropped_timestamps;  // colour frames without an interpolable ground-truth pose
};

// Reads static_dir (TUM layout with groundtruth.txt), composites textured moving objects (depth
// test against the real depth: the object wins where nearer or where the real depth is 0), writes
// out_dir in the TUM layout with masks/, groundtruth.txt at the colour timestamps, camera.txt and
// scene.json. Throws InputError on a missing folder or ground truth, an empty frame range, or a
// non-empty out_dir without overwrite.
AugmentReport augmentSequence(const std::string& static_dir, const std::string& out_dir,
                              const AugmentConfig& config, const SequenceOptions& options = {},
                              bool overwrite = false);

}  // namespace ff::synth

// `flowfusion augment`: textured moving objects composited into a real static sequence.
#include <algorithm>
#include <filesystem>
#include <vector>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/sensor_band.h"
#include "flowfusion/synth/people.h"
#include "flowfusion/synth/scene_model.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff::synth {

namespace {

constexpr uint64_t kAugmentStream = 0x41554730ULL, kAugmentNoise = 0x41554e30ULL, kAugmentPeople = 0x41555050ULL;
// A hole in the real depth hides what lies behind the valid depth enclosing it within 1/10 of the
// image width (64 px at VGA: the black monitor of TUM fr1's desk returns speckles that close).
constexpr int kHoleReachFraction = 10;

void validate(const AugmentConfig& c) {
  const auto bad = [](const std::string& what) { throw InputError("augment configuration: " + what); };
  if (c.objects < 0 || c.objects > 32) bad("objects must be in 0..32, got " + std::to_string(c.objects));
  if (c.people < 0 || c.people > 8) bad("people must be in 0..8, got " + std::to_string(c.people));
  if (c.objects + c.people < 1) bad("need at least one object or person (objects + people >= 1)");
  if (!(c.camera_height > 0.3 && c.camera_height < 3)) bad("camera_height must be in (0.3, 3) m");
  if (!(c.min_distance > 0.1 && c.max_distance >= c.min_distance && c.max_distance < 10))
    bad("need 0.1 < min_distance <= max_distance < 10 m");
  if (!(c.object_speed >= 0 && c.object_speed <= 5)) bad("object_speed must be in [0, 5] m/s");
  if (!(c.max_pose_gap > 0)) bad("max_pose_gap must be > 0 s");
  if (c.first_frame < 0) bad("first frame must be >= 0, got " + std::to_string(c.first_frame));
}

// People walk on a floor camera_height below the first camera (world z up), across its view as seen
// on the floor, 1.0-1.6 m in front of it.
void addPeople(SceneModel& model, const AugmentConfig& config, const SE3& T_world_cam0, double duration_s) {
  Rng rng(hashCombine(config.seed, kAugmentPeople));
  const Eigen::Vector3d eye = T_world_cam0.translation(), view = T_world_cam0.linear().col(2);
  SE3 T_world_floor = SE3::Identity();
  T_world_floor.translation().z() = eye.z() - config.camera_height;
  WalkLine line;
  line.eye = eye.head<2>();
  line.view = view.head<2>().norm() > 1e-6 ? Eigen::Vector2d(view.head<2>().normalized()) : Eigen::Vector2d::UnitX();
  for (int k = 0; k < config.people; ++k) {
    line.distance_m = rng.uniform(1.0, 1.6);
    line.half_m = rng.uniform(0.9, 1.3);
    const auto body = walkerScript(rng, line, -rng.uniform(0.0, 1.5), duration_s + 1.0, T_world_floor);
    for (MovingObject& o : personObjects(model, rng, body, k)) model.objects.push_back(std::move(o));
  }
}

// The frames first_frame..last_frame with a ground-truth pose (index, T_world_cam); the others'
// timestamps into report.dropped_timestamps. InputError naming the folder when the range is empty.
std::vector<std::pair<int, SE3>> posedFrames(const TumSequence& seq, const AugmentConfig& config,
                                             const std::string& static_dir, AugmentReport& report) {
  const int n = static_cast<int>(seq.size());
  const int last = config.last_frame < 0 ? n - 1 : config.last_frame;
  if (config.first_frame >= n || last >= n || last < config.first_frame)
    throw InputError(static_dir + ": frame range " + std::to_string(config.first_frame) + ":" +
                     std::to_string(config.last_frame) + " is empty or outside the " + std::to_string(n) +
                     " associated frames");
  std::vector<std::pair<int, SE3>> kept;
  for (int i = config.first_frame; i <= last; ++i) {
    SE3 T;
    const double t = seq.entry(i).rgb_timestamp;
    if (interpolatePose(*seq.groundtruth(), t, T, config.max_pose_gap))
      kept.emplace_back(i, T);
    else
      report.dropped_timestamps.push_back(t);
  }
  if (kept.empty())
    throw InputError(static_dir + ": none of the colour frames " + std::to_string(config.first_frame) + ".." +
                     std::to_string(last) + " has a ground-truth pose (groundtruth.txt does not cover them)");
  return kept;
}

// The boxes (some L-shaped pairs) crossing the first camera's view, the people, and a light.
SceneModel augmentModel(const AugmentConfig& config, const CameraIntrinsics& camera, const SE3& T_world_cam0,
                        double duration_s) {
  SceneModel model;
  Rng rng(hashCombine(config.seed, kAugmentStream));
  const double tan_x = 0.5 * camera.width / camera.fx, tan_y = 0.5 * camera.height / camera.fy;
  for (int k = 0; k < config.objects; ++k) {
    MovingObject obj;
    obj.shape = centred(boxShape(model, rng, 0.15, 0.4));
    if (rng.chance(0.4)) {  // an L-shaped pair of boxes: concave silhouettes, self-occlusion
      const Item second = centred(boxShape(model, rng, 0.1, 0.25));
      for (Part p : second.parts) {
        const Eigen::Vector3d shift(obj.shape.hi.x() + 0.5 * (p.hi.x() - p.lo.x()), 0, obj.shape.lo.z() - p.lo.z());
        p.lo += shift;
        p.hi += shift;
        obj.shape.add(p);
      }
      obj.shape.kind = "l_shape";
    }
    const auto path = crossingPath(rng, T_world_cam0, tan_x, tan_y, config.min_distance, config.max_distance,
                                   config.object_speed);
    obj.path = path;
    model.objects.push_back(std::move(obj));
  }
  addPeople(model, config, T_world_cam0, duration_s);
  // A light above and behind the first camera, so the objects are lit roughly like the room.
  model.light.position = T_world_cam0 * Eigen::Vector3d(0.5, -2.0, -0.5);
  model.light.ambient = 0.45;
  model.light.diffuse = 0.8;
  return model;
}

// A real frame with the rendered objects pasted where they are in front of the real depth.
struct Composite {
  cv::Mat color, depth;
  cv::Mat mask;  // CV_8U, 255 = a pasted (moving) pixel
};

// The nearer of two depths where both are valid, else the valid one (0: neither).
float nearerValid(float a, float b) { return a > 0 && b > 0 ? std::min(a, b) : std::max(a, b); }

// Along each row (transpose for columns), per pixel without depth, from the nearest valid depth
// before and after it: `enclosed` the farther of the two where both lie within reach_px (else 0),
// `beside` the nearer of those found at any distance along the line (0 where neither is).
struct HoleSides {
  cv::Mat enclosed, beside;  // CV_32F
};
HoleSides holeSidesAlongRows(const cv::Mat& depth, int reach_px) {
  HoleSides out{cv::Mat(depth.size(), CV_32F, cv::Scalar(0)), cv::Mat(depth.size(), CV_32F, cv::Scalar(0))};
  std::vector<int> last_before(depth.cols);
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = depth.ptr<float>(v);
    float* enclosed = out.enclosed.ptr<float>(v);
    float* beside = out.beside.ptr<float>(v);
    for (int u = 0, last = -1; u < depth.cols; ++u) {
      if (z[u] > 0) last = u;
      last_before[u] = last;
    }
    for (int u = depth.cols - 1, next = -1; u >= 0; --u) {
      if (z[u] > 0) next = u;
      const int last = last_before[u];
      const float before = last >= 0 ? z[last] : 0.f, after = next >= 0 ? z[next] : 0.f;
      const bool both_near = last >= 0 && u - last <= reach_px && next >= 0 && next - u <= reach_px;
      enclosed[u] = both_near ? std::max(before, after) : 0.f;
      beside[u] = nearerValid(before, after);
    }
  }
  return out;
}

HoleSides holeSidesAlongColumns(const cv::Mat& depth, int reach_px) {
  const HoleSides t = holeSidesAlongRows(depth.t(), reach_px);
  HoleSides out;
  cv::transpose(t.enclosed, out.enclosed);
  cv::transpose(t.beside, out.beside);
  return out;
}

// The depth in front of which a pasted object shows, per pixel: the real depth where the sensor
// measured one; in a hole, the surface the hole lies within, when valid depth encloses it on both
// sides of a row or of a column within reach_px (a black monitor's speckles: a person behind the
// monitor stays hidden where its screen returned nothing). A hole open to one side, such as the
// shadow beside a depth edge or the sensor's invalid band at the image border, shows the object
// (0), unless the real colour there is black (grey below kBlackGrey): a black surface returns no
// depth, so a black screen too large to be enclosed, or cut by the image's edge, is taken to
// continue the nearest surface beside it along its row or column, its own frame (HoleTest::
// BlackSurfaces; HoleTest::Enclosed leaves such holes open, as generator version 2 did).
cv::Mat occludingDepth(const cv::Mat& depth, const cv::Mat& color, int reach_px, HoleTest holes) {
  const HoleSides rows = holeSidesAlongRows(depth, reach_px), cols = holeSidesAlongColumns(depth, reach_px);
  cv::Mat grey;
  cv::cvtColor(color, grey, cv::COLOR_BGR2GRAY);
  const int black = static_cast<int>(kBlackGrey * 255.f);
  cv::Mat out = depth.clone();
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      if (depth.at<float>(v, u) > 0) continue;
      float z = nearerValid(rows.enclosed.at<float>(v, u), cols.enclosed.at<float>(v, u));
      if (z == 0 && holes == HoleTest::BlackSurfaces && grey.at<uchar>(v, u) < black)
        z = nearerValid(rows.beside.at<float>(v, u), cols.beside.at<float>(v, u));
      out.at<float>(v, u) = z;
    }
  return out;
}

Composite composite(const RgbdFrame& real, const RenderedLayer& layer, const RenderOptions& opt, HoleTest holes,
                    BandDepth band_depth) {
  const cv::Mat obj_color = finishColor(layer.color, opt);
  const cv::Mat obj_depth = kinectDepth(layer.depth_clean, layer.cos_incidence, opt);
  const cv::Mat z_front =
      occludingDepth(real.depth, real.color, std::max(1, real.depth.cols / kHoleReachFraction), holes);
  Composite c{real.color.clone(), real.depth.clone(), cv::Mat(real.depth.rows, real.depth.cols, CV_8U, cv::Scalar(0))};
  for (int v = 0; v < c.mask.rows; ++v)
    for (int u = 0; u < c.mask.cols; ++u) {
      if (!layer.object_id.at<uint8_t>(v, u)) continue;
      const float z_real = z_front.at<float>(v, u);
      if (z_real > 0 && layer.depth_clean.at<float>(v, u) >= z_real) continue;
      c.mask.at<uint8_t>(v, u) = 255;
      c.color.at<cv::Vec3b>(v, u) = obj_color.at<cv::Vec3b>(v, u);
      c.depth.at<float>(v, u) = obj_depth.at<float>(v, u);
    }
  if (band_depth == BandDepth::None) c.depth.setTo(0.f, SensorBand::of(real.depth).pixels(c.depth.size()) & c.mask);
  // Soften the pasted edges as the real camera's blur would (colour only; depth and mask stay exact).
  cv::Mat band, dil, ero, soft;
  cv::dilate(c.mask, dil, cv::Mat());
  cv::erode(c.mask, ero, cv::Mat());
  cv::subtract(dil, ero, band);
  cv::GaussianBlur(c.color, soft, cv::Size(0, 0), 0.6);
  soft.copyTo(c.color, band);
  return c;
}

void writeSceneJson(const std::string& out_dir, const std::string& static_dir, const AugmentConfig& config,
                    const AugmentReport& report, const SceneModel& model) {
  nlohmann::json j;
  j["generator"] = "flowfusion augment";
  j["generator_version"] = kGeneratorVersion;
  j["seed"] = config.seed;
  j["config"] = config;
  j["source"] = static_dir;
  j["dropped_timestamps"] = report.dropped_timestamps;
  j["textures"] = model.texture_names;
  j["objects"] = nlohmann::json::array();
  for (const MovingObject& o : model.objects) {
    nlohmann::json oj = o.shape.describe();
    oj["size_m"] = jsonVec(o.shape.hi - o.shape.lo);
    oj["path"] = o.path->describe();
    j["objects"].push_back(oj);
  }
  writeJsonFile((std::filesystem::path(out_dir) / "scene.json").string(), j);
}

}  // namespace

AugmentReport augmentSequence(const std::string& static_dir, const std::string& out_dir,
                              const AugmentConfig& config, const SequenceOptions& options, bool overwrite) {
  validate(config);
  if (!std::filesystem::is_directory(static_dir)) throw InputError(static_dir + ": no such folder");
  const TumSequence seq = TumSequence::open(static_dir, options);
  if (!seq.groundtruth())
    throw InputError(static_dir + ": no groundtruth.txt; augment needs the ground-truth camera poses");
  AugmentReport report;
  const std::vector<std::pair<int, SE3>> kept = posedFrames(seq, config, static_dir, report);
  prepareOutputDir(out_dir, overwrite);

  const CameraIntrinsics& camera = seq.camera();
  const SE3 T_world_cam0 = kept.front().second;
  const double t0 = seq.entry(kept.front().first).rgb_timestamp;
  const SceneModel model =
      augmentModel(config, camera, T_world_cam0, seq.entry(kept.back().first).rgb_timestamp - t0);
  RenderOptions opt;
  opt.camera = camera;
  opt.noise = config.noise;
  opt.depth_shadows = false;  // the real background carries its own shadows
  opt.psf_sigma_px = 0;       // edges are blended after compositing

  TumWriter writer(out_dir, camera);
  for (const auto& [index, T_world_cam] : kept) {
    const RgbdFrame real = seq.load(index);
    const double t = real.timestamp;
    opt.noise_key = hashCombine(hashCombine(config.seed, kAugmentNoise), static_cast<uint64_t>(std::llround(t * 1e6)));
    const Composite c = composite(real, model.cast(T_world_cam, t - t0, camera), opt, config.holes, config.band_depth);
    // The real depth keeps its own time: out of step with the colour, as the sensor took it.
    writer.add(t, c.color, c.depth, T_world_cam, c.mask, real.depth_timestamp);
  }
  writer.finish("flowfusion augment of " + static_dir + ", seed " + std::to_string(config.seed) +
                ", generator version " + std::to_string(kGeneratorVersion));
  writeSceneJson(out_dir, static_dir, config, report, model);
  report.frames_written = static_cast<int>(kept.size());
  return report;
}

}  // namespace ff::synth

// `flowfusion augment`: textured moving objects composited into a real static sequence.
#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/synth/scene_model.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace ff::synth {

namespace {

constexpr uint64_t kAugmentStream = 0x41554730ULL, kAugmentNoise = 0x41554e30ULL;

// Objects live in the world frame but are laid out in the frame of the first camera: they start
// in front of it and oscillate mostly sideways (so they cross the view), tumbling about their
// own axis.
class CameraRelativePath : public ObjectPath {
 public:
  SE3 T_world_cam0 = SE3::Identity();
  Eigen::Vector3d p0_cam0 = Eigen::Vector3d::Zero();  // m
  std::array<Sinusoids, 3> offset;                     // cam0 x, y, z offsets, m
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();    // initial orientation in cam0
  Eigen::Vector3d spin_axis = Eigen::Vector3d::UnitY();
  Sinusoids spin;  // rad

  SE3 T_world_object(double t) const override {
    SE3 T_cam0_obj = SE3::Identity();
    T_cam0_obj.linear() = R0 * Eigen::AngleAxisd(spin.value(t), spin_axis).toRotationMatrix();
    T_cam0_obj.translation() = p0_cam0 + Eigen::Vector3d(offset[0].value(t), offset[1].value(t), offset[2].value(t));
    return T_world_cam0 * T_cam0_obj;
  }
  double rmsSpeed() const {
    double s = 0;
    for (const auto& o : offset) s += o.rmsDerivative() * o.rmsDerivative();
    return std::sqrt(s);
  }
  nlohmann::json describe() const override {
    const Eigen::Quaterniond q(T_world_cam0.linear());
    return {{"type", "camera0_relative"},
            {"T_world_cam0", {T_world_cam0.translation().x(), T_world_cam0.translation().y(),
                              T_world_cam0.translation().z(), q.x(), q.y(), q.z(), q.w()}},
            {"p0_cam0_m", jsonVec(p0_cam0)}, {"x_m", offset[0].describe()}, {"y_m", offset[1].describe()},
            {"z_m", offset[2].describe()}, {"spin_axis", jsonVec(spin_axis)}, {"spin_rad", spin.describe()}};
  }
};

void validate(const AugmentConfig& c) {
  const auto bad = [](const std::string& what) { throw InputError("augment configuration: " + what); };
  if (c.objects < 1 || c.objects > 32) bad("objects must be in 1..32, got " + std::to_string(c.objects));
  if (!(c.min_distance > 0.1 && c.max_distance >= c.min_distance && c.max_distance < 10))
    bad("need 0.1 < min_distance <= max_distance < 10 m");
  if (!(c.object_speed >= 0 && c.object_speed <= 5)) bad("object_speed must be in [0, 5] m/s");
  if (!(c.max_pose_gap > 0)) bad("max_pose_gap must be > 0 s");
  if (c.first_frame < 0) bad("first frame must be >= 0, got " + std::to_string(c.first_frame));
}

Item centred(Item shape) {
  const Eigen::Vector3d mid = 0.5 * (shape.lo + shape.hi);
  Item out;
  out.kind = shape.kind;
  for (Part p : shape.parts) {
    p.lo -= mid;
    p.hi -= mid;
    out.add(p);
  }
  return out;
}

}  // namespace

AugmentReport augmentSequence(const std::string& static_dir, const std::string& out_dir,
                              const AugmentConfig& config, const SequenceOptions& options, bool overwrite) {
  validate(config);
  if (!std::filesystem::is_directory(static_dir)) throw InputError(static_dir + ": no such folder");
  const TumSequence seq = TumSequence::open(static_dir, options);
  if (!seq.groundtruth())
    throw InputError(static_dir + ": no groundtruth.txt; augment needs the ground-truth camera poses");
  const int n = static_cast<int>(seq.size());
  const int last = config.last_frame < 0 ? n - 1 : config.last_frame;
  if (config.first_frame >= n || last >= n || last < config.first_frame)
    throw InputError(static_dir + ": frame range " + std::to_string(config.first_frame) + ":" +
                     std::to_string(config.last_frame) + " is empty or outside the " + std::to_string(n) +
                     " associated frames");

  AugmentReport report;
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
  prepareOutputDir(out_dir, overwrite);

  const CameraIntrinsics& camera = seq.camera();
  const SE3 T_world_cam0 = kept.front().second;
  const double t0 = seq.entry(kept.front().first).rgb_timestamp;
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
    auto path = std::make_shared<CameraRelativePath>();
    path->T_world_cam0 = T_world_cam0;
    const double z = rng.uniform(config.min_distance, config.max_distance);
    path->p0_cam0 = Eigen::Vector3d(rng.uniform(-0.4, 0.4) * z * tan_x, rng.uniform(-0.3, 0.3) * z * tan_y, z);
    path->offset[0] = randomSinusoids(rng, {{rng.uniform(0.5, 0.8) * z * tan_x, 0.1}, {0.05, 0.3}});
    path->offset[1] = randomSinusoids(rng, {{0.15 * z * tan_y, 0.15}});
    path->offset[2] = randomSinusoids(rng, {{0.1 * z, 0.12}});
    path->R0 = (Eigen::AngleAxisd(rng.uniform(0, 2 * M_PI), Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rng.uniform(-0.4, 0.4), Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
    path->spin_axis = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()).normalized();
    path->spin = randomSinusoids(rng, {{rng.uniform(0.5, 1.5), 0.1}});
    const double k_t = config.object_speed / std::max(1e-9, path->rmsSpeed());
    for (auto& o : path->offset) o.scaleTime(k_t);
    path->spin.scaleTime(k_t);
    obj.path = path;
    model.objects.push_back(std::move(obj));
  }
  // A light above and behind the first camera, so the objects are lit roughly like the room.
  model.light.position = T_world_cam0 * Eigen::Vector3d(0.5, -2.0, -0.5);
  model.light.ambient = 0.45;
  model.light.diffuse = 0.8;

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
    const RenderedLayer layer = model.cast(T_world_cam, t - t0, camera);
    const cv::Mat obj_color = finishColor(layer.color, opt);
    const cv::Mat obj_depth = kinectDepth(layer.depth_clean, layer.cos_incidence, opt);
    cv::Mat color = real.color.clone(), depth = real.depth.clone();
    cv::Mat mask(camera.height, camera.width, CV_8U, cv::Scalar(0));
    for (int v = 0; v < camera.height; ++v)
      for (int u = 0; u < camera.width; ++u) {
        if (!layer.object_id.at<uint8_t>(v, u)) continue;
        const float z_real = real.depth.at<float>(v, u);
        if (z_real > 0 && layer.depth_clean.at<float>(v, u) >= z_real) continue;
        mask.at<uint8_t>(v, u) = 255;
        color.at<cv::Vec3b>(v, u) = obj_color.at<cv::Vec3b>(v, u);
        depth.at<float>(v, u) = obj_depth.at<float>(v, u);
      }
    // Soften the pasted edges as the real camera's blur would (colour only; depth and mask stay exact).
    cv::Mat band, dil, ero, soft;
    cv::dilate(mask, dil, cv::Mat());
    cv::erode(mask, ero, cv::Mat());
    cv::subtract(dil, ero, band);
    cv::GaussianBlur(color, soft, cv::Size(0, 0), 0.6);
    soft.copyTo(color, band);
    writer.add(t, color, depth, T_world_cam, mask);
  }
  writer.finish("flowfusion augment of " + static_dir + ", seed " + std::to_string(config.seed) +
                ", generator version " + std::to_string(kGeneratorVersion));
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
  report.frames_written = static_cast<int>(kept.size());
  return report;
}

}  // namespace ff::synth

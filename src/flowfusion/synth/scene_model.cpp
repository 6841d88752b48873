#include "flowfusion/synth/scene_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "flowfusion/synth/synthetic_scene.h"

namespace ff::synth {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Ray {
  Eigen::Vector3d o, d, inv;
  Ray(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) : o(origin), d(dir) {
    for (int i = 0; i < 3; ++i) {
      const double di = std::fabs(d[i]) < 1e-12 ? (d[i] < 0 ? -1e-12 : 1e-12) : d[i];
      inv[i] = 1.0 / di;
    }
  }
};

// Entry distance of the ray into box [lo, hi] if it enters in front of the origin and before
// t_max; axis = the face's axis.
inline bool slab(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Ray& r, double t_max, double& t,
                 int& axis) {
  double t_near = -kInf, t_far = kInf;
  for (int i = 0; i < 3; ++i) {
    double a = (lo[i] - r.o[i]) * r.inv[i], b = (hi[i] - r.o[i]) * r.inv[i];
    if (a > b) std::swap(a, b);
    if (a > t_near) {
      t_near = a;
      axis = i;
    }
    t_far = std::min(t_far, b);
  }
  if (t_near > t_far || t_near <= 1e-9 || t_near >= t_max) return false;
  t = t_near;
  return true;
}

inline bool boundsHit(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Ray& r, double t_max) {
  double t_near = -kInf, t_far = kInf;
  for (int i = 0; i < 3; ++i) {
    double a = (lo[i] - r.o[i]) * r.inv[i], b = (hi[i] - r.o[i]) * r.inv[i];
    if (a > b) std::swap(a, b);
    t_near = std::max(t_near, a);
    t_far = std::min(t_far, b);
  }
  return t_near <= t_far && t_far > 0 && t_near < t_max;
}

// Texture coordinates on the face with normal along `axis`: vertical faces use (horizontal, up)
// so that textures stand upright.
inline Eigen::Vector2d faceUv(const Eigen::Vector3d& p, int axis) {
  switch (axis) {
    case 0: return {p.y(), p.z()};
    case 1: return {p.x(), p.z()};
    default: return {p.x(), p.y()};
  }
}

struct Hit {
  double t = kInf;
  const Part* part = nullptr;
  int axis = 0;
  int object = -1;  // -1 = static
};

inline void castItem(const Item& item, const Ray& r, Hit& hit, int object) {
  if (!boundsHit(item.lo, item.hi, r, hit.t)) return;
  for (const Part& p : item.parts) {
    double t;
    int axis;
    if (slab(p.lo, p.hi, r, hit.t, t, axis)) {
      hit.t = t;
      hit.part = &p;
      hit.axis = axis;
      hit.object = object;
    }
  }
}

}  // namespace

nlohmann::json jsonVec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

void Item::add(const Part& p) {
  if (parts.empty()) {
    lo = p.lo;
    hi = p.hi;
  } else {
    lo = lo.cwiseMin(p.lo);
    hi = hi.cwiseMax(p.hi);
  }
  parts.push_back(p);
}

nlohmann::json Item::describe() const {
  nlohmann::json j{{"kind", kind}, {"parts", nlohmann::json::array()}};
  for (const Part& p : parts) j["parts"].push_back({{"min_m", jsonVec(p.lo)}, {"max_m", jsonVec(p.hi)}, {"texture", p.texture}});
  return j;
}

double Sinusoids::value(double t) const {
  double v = 0;
  for (const auto& [a, w, phi] : terms) v += a * std::sin(w * t + phi);
  return v;
}

double Sinusoids::derivative(double t) const {
  double v = 0;
  for (const auto& [a, w, phi] : terms) v += a * w * std::cos(w * t + phi);
  return v;
}

double Sinusoids::rmsDerivative() const {
  double s = 0;
  for (const auto& [a, w, phi] : terms) s += 0.5 * a * a * w * w;
  return std::sqrt(s);
}

void Sinusoids::scaleTime(double k) {
  for (auto& term : terms) term[1] *= k;
}

nlohmann::json Sinusoids::describe() const {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [a, w, phi] : terms) j.push_back({{"amplitude", a}, {"omega_rad_s", w}, {"phase_rad", phi}});
  return j;
}

SE3 CameraPath::T_world_cam(double t_sequence) const {
    const double t = t_sequence + start_s;
    // Camera looking along world +x with zero angles: cam z = world x, cam x = -world y, cam y = -world z.
    Eigen::Matrix3d R0;
    R0 << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    const double round = loop_rate * t;  // rad round the loop
    const double y = yaw0 + round + yaw.value(t), p = pitch0 + pitch.value(t), r = roll.value(t);
    SE3 T = SE3::Identity();
    T.linear() = (Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-p, Eigen::Vector3d::UnitY()))
                     .toRotationMatrix() *
                 R0 * Eigen::AngleAxisd(r, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = centre + Eigen::Vector3d(position[0].value(t), position[1].value(t), position[2].value(t)) +
                      loop_radius_m * Eigen::Vector3d(std::cos(yaw0 + round), std::sin(yaw0 + round), 0);
    return T;
  }
nlohmann::json CameraPath::describe() const {
  nlohmann::json j = {{"centre_m", jsonVec(centre)}, {"yaw0_rad", yaw0}, {"pitch0_rad", pitch0},
          {"x_m", position[0].describe()}, {"y_m", position[1].describe()}, {"z_m", position[2].describe()},
          {"yaw_rad", yaw.describe()}, {"pitch_rad", pitch.describe()}, {"roll_rad", roll.describe()},
          {"loop_radius_m", loop_radius_m}, {"loop_rate_rad_per_s", loop_rate}};
  if (start_s != 0) j["start_s"] = start_s;
  return j;
}

SE3 CameraRelativePath::T_world_object(double t) const {
  SE3 T_cam0_obj = SE3::Identity();
  T_cam0_obj.linear() = R0 * Eigen::AngleAxisd(spin.value(t), spin_axis).toRotationMatrix();
  T_cam0_obj.translation() = p0_cam0 + Eigen::Vector3d(offset[0].value(t), offset[1].value(t), offset[2].value(t));
  return T_world_cam0 * T_cam0_obj;
}

double CameraRelativePath::rmsSpeed() const {
  double s = 0;
  for (const auto& o : offset) s += o.rmsDerivative() * o.rmsDerivative();
  return std::sqrt(s);
}

nlohmann::json CameraRelativePath::describe() const {
  const Eigen::Quaterniond q(T_world_cam0.linear());
  return {{"type", "camera0_relative"},
          {"T_world_cam0", {T_world_cam0.translation().x(), T_world_cam0.translation().y(),
                            T_world_cam0.translation().z(), q.x(), q.y(), q.z(), q.w()}},
          {"p0_cam0_m", jsonVec(p0_cam0)}, {"x_m", offset[0].describe()}, {"y_m", offset[1].describe()},
          {"z_m", offset[2].describe()}, {"spin_axis", jsonVec(spin_axis)}, {"spin_rad", spin.describe()}};
}

std::shared_ptr<CameraRelativePath> crossingPath(Rng& rng, const SE3& T_world_cam0, double tan_x, double tan_y,
                                                 double min_distance, double max_distance, double speed_mps) {
  auto path = std::make_shared<CameraRelativePath>();
  path->T_world_cam0 = T_world_cam0;
  const double z = rng.uniform(min_distance, max_distance);
  path->p0_cam0 = Eigen::Vector3d(rng.uniform(-0.4, 0.4) * z * tan_x, rng.uniform(-0.3, 0.3) * z * tan_y, z);
  path->offset[0] = randomSinusoids(rng, {{rng.uniform(0.5, 0.8) * z * tan_x, 0.1}, {0.05, 0.3}});
  path->offset[1] = randomSinusoids(rng, {{0.15 * z * tan_y, 0.15}});
  path->offset[2] = randomSinusoids(rng, {{0.1 * z, 0.12}});
  path->R0 = (Eigen::AngleAxisd(rng.uniform(0, 2 * M_PI), Eigen::Vector3d::UnitY()) *
              Eigen::AngleAxisd(rng.uniform(-0.4, 0.4), Eigen::Vector3d::UnitX()))
                 .toRotationMatrix();
  path->spin_axis = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal()).normalized();
  path->spin = randomSinusoids(rng, {{rng.uniform(0.5, 1.5), 0.1}});
  const double k_t = speed_mps / std::max(1e-9, path->rmsSpeed());
  for (auto& o : path->offset) o.scaleTime(k_t);
  path->spin.scaleTime(k_t);
  return path;
}

Sinusoids randomSinusoids(Rng& rng, const std::vector<std::pair<double, double>>& amp_freq_hz) {
  Sinusoids s;
  for (const auto& [a, f] : amp_freq_hz)
    s.terms.push_back({a * rng.uniform(0.7, 1.3), 2 * M_PI * f * rng.uniform(0.75, 1.25), rng.uniform(0, 2 * M_PI)});
  return s;
}

Part box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int texture, Rng& rng, float albedo) {
  Part p;
  p.lo = lo;
  p.hi = hi;
  p.texture = texture;
  p.offset_m = Eigen::Vector2d(rng.uniform(0, 3), rng.uniform(0, 3));
  p.albedo = albedo * static_cast<float>(rng.uniform(0.9, 1.1));
  return p;
}

Item personShape(SceneModel& m, Rng& rng) {
  const double s = rng.uniform(0.92, 1.08);
  const int trousers = m.addTexture(Material::Clothing, rng), shirt = m.addTexture(Material::Clothing, rng);
  const int skin = m.addTexture(Material::Skin, rng), hair = m.addTexture(Material::Fabric, rng);
  Item it;
  it.kind = "person";
  const auto add = [&](double x0, double x1, double y0, double y1, double z0, double z1, int tex, float albedo = 1.0f) {
    it.add(box(s * Eigen::Vector3d(x0, y0, z0), s * Eigen::Vector3d(x1, y1, z1), tex, rng, albedo));
  };
  add(-0.08, 0.08, 0.02, 0.17, 0, 0.86, trousers);
  add(-0.08, 0.08, -0.17, -0.02, 0, 0.86, trousers);
  add(-0.12, 0.12, -0.21, 0.21, 0.86, 1.46, shirt);
  add(-0.06, 0.06, 0.21, 0.3, 0.82, 1.44, shirt, 0.95f);
  add(-0.06, 0.06, -0.3, -0.21, 0.82, 1.44, shirt, 0.95f);
  add(-0.05, 0.05, -0.05, 0.05, 1.46, 1.5, skin);
  add(-0.1, 0.1, -0.09, 0.09, 1.5, 1.7, skin);
  add(-0.11, 0.06, -0.1, 0.1, 1.66, 1.74, hair, 0.5f);
  return it;
}

Item boxShape(SceneModel& m, Rng& rng, double min_side, double max_side) {
  const Material mat = rng.chance(0.5) ? Material::Cardboard : Material::Poster;
  const int tex = m.addTexture(mat, rng);
  const Eigen::Vector3d size(rng.uniform(min_side, max_side), rng.uniform(min_side, max_side),
                             rng.uniform(min_side, max_side * 1.3));
  Item it;
  it.kind = "box";
  it.add(box(Eigen::Vector3d(-size.x() / 2, -size.y() / 2, 0), Eigen::Vector3d(size.x() / 2, size.y() / 2, size.z()),
             tex, rng));
  return it;
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

int SceneModel::addTexture(Material m, Rng& rng) {
  textures.push_back(makeTexture(m, rng));
  texture_names.emplace_back(materialName(m));
  return static_cast<int>(textures.size()) - 1;
}

namespace {

// An item's bounds projected to a pixel rectangle; the whole image when a corner is near or
// behind the camera.
cv::Rect2d screenRect(const Item& item, const SE3& T_cam_item, const CameraIntrinsics& camera) {
  double u0 = kInf, v0 = kInf, u1 = -kInf, v1 = -kInf;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p_i(c & 1 ? item.hi.x() : item.lo.x(), c & 2 ? item.hi.y() : item.lo.y(),
                              c & 4 ? item.hi.z() : item.lo.z());
    const Eigen::Vector3d p_c = T_cam_item * p_i;
    if (p_c.z() < 0.05) return cv::Rect2d(0, 0, camera.width, camera.height);
    const Eigen::Vector2d px = camera.project(p_c);
    u0 = std::min(u0, px.x());
    v0 = std::min(v0, px.y());
    u1 = std::max(u1, px.x());
    v1 = std::max(v1, px.y());
  }
  return cv::Rect2d(u0 - 1, v0 - 1, u1 - u0 + 2, v1 - v0 + 2);
}

// The colour of a hit: the part's texture, filtered over the pixel's footprint, times the light.
cv::Vec3f shadeHit(const SceneModel& m, const Part& part, const Ray& ray_w, double t, const Eigen::Vector3d& p_w,
                   const Eigen::Vector3d& n_w, const Eigen::Vector2d& uv, double cos_i, double pixel_angle) {
  const double dist = t * ray_w.d.norm();
  const double footprint = dist * pixel_angle / std::sqrt(std::max(cos_i, 0.05));
  const cv::Vec3f albedo =
      m.textures[part.texture].sample(uv.x() + part.offset_m.x(), uv.y() + part.offset_m.y(), footprint) * part.albedo;
  const Eigen::Vector3d to_light = m.light.position - p_w;
  const double l = to_light.norm();
  const double ndl = std::max(0.0, n_w.dot(to_light) / l);
  const double f2 = m.light.falloff_m * m.light.falloff_m;
  const double shade = m.light.ambient + m.light.diffuse * ndl * f2 / (f2 + l * l);
  return albedo * static_cast<float>(shade);
}

// A moving object at one instant, as the camera's rays see it.
struct PosedObject {
  Eigen::Matrix3d R_oc;  // camera ray directions into the object frame
  Eigen::Matrix3d R_wo;
  Eigen::Vector3d o_o;   // camera centre in the object frame
};

std::vector<PosedObject> posedObjects(const std::vector<MovingObject>& objects, const SE3& T_world_cam, double time_s) {
  const Eigen::Matrix3d R_wc = T_world_cam.linear();
  const Eigen::Vector3d o_w = T_world_cam.translation();
  std::vector<PosedObject> posed;
  for (const MovingObject& obj : objects) {
    const SE3 T_wo = obj.path->T_world_object(time_s);
    const Eigen::Matrix3d R_ow = T_wo.linear().transpose();
    posed.push_back({R_ow * R_wc, T_wo.linear(), R_ow * (o_w - T_wo.translation())});
  }
  return posed;
}

// Inside the room a ray leaves through the nearest far face: that face into hit.
void castRoom(const Room& room, const Ray& ray_w, Hit& hit) {
  double t_far = kInf;
  int room_face = -1;
  for (int i = 0; i < 3; ++i) {
    const double b = ((ray_w.d[i] > 0 ? room.size[i] : 0.0) - ray_w.o[i]) * ray_w.inv[i];
    if (b < t_far) {
      t_far = b;
      room_face = 2 * i + (ray_w.d[i] > 0 ? 1 : 0);
    }
  }
  if (t_far > 0) {
    hit.t = t_far;
    hit.axis = room_face / 2;
    hit.part = &room.faces[room_face];
  }
}

// One pixel of a RenderedLayer (all 0 where the ray hits nothing).
struct PixelSample {
  cv::Vec3f color = cv::Vec3f(0, 0, 0);
  float depth = 0;
  uint8_t object_id = 0;
  float cos_incidence = 0;
};

// The camera's view of a tile: what its pixels' rays test (the items and objects whose screen
// rectangles overlap the tile) and the camera's pose.
struct TileView {
  const SceneModel& model;
  const std::vector<PosedObject>& posed;
  const std::vector<const Item*>& items;
  const std::vector<int>& objects;
  Eigen::Matrix3d R_wc;
  Eigen::Vector3d o_w;
  double pixel_angle;  // radians one pixel subtends, for texture filtering
};

// The ray along camera direction d_c (unnormalised, z = 1, so that the ray parameter t is the
// depth of the hit) through the room, the tile's furniture and objects, shaded.
PixelSample castPixel(const TileView& view, const Eigen::Vector3d& d_c) {
  const SceneModel& m = view.model;
  const Ray ray_w(view.o_w, view.R_wc * d_c);
  Hit hit;
  if (m.room) castRoom(*m.room, ray_w, hit);
  for (const Item* item : view.items) castItem(*item, ray_w, hit, -1);
  Eigen::Vector3d p_local;
  for (int k : view.objects) {
    const Ray ray_o(view.posed[k].o_o, view.posed[k].R_oc * d_c);
    const Part* before = hit.part;
    castItem(m.objects[k].shape, ray_o, hit, k);
    if (hit.part != before) p_local = ray_o.o + hit.t * ray_o.d;
  }
  if (!hit.part) return {};
  const Eigen::Vector3d p_w = view.o_w + hit.t * ray_w.d;
  Eigen::Vector3d n_w = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv;
  if (hit.object >= 0) {
    Eigen::Vector3d n_o = Eigen::Vector3d::Zero();
    const Eigen::Vector3d d_o = view.posed[hit.object].R_oc * d_c;
    n_o[hit.axis] = d_o[hit.axis] > 0 ? -1.0 : 1.0;
    n_w = view.posed[hit.object].R_wo * n_o;
    uv = faceUv(p_local, hit.axis);
  } else {
    n_w[hit.axis] = ray_w.d[hit.axis] > 0 ? -1.0 : 1.0;
    uv = faceUv(p_w, hit.axis);
  }
  const double cos_i = std::fabs(n_w.dot(ray_w.d)) / ray_w.d.norm();
  return {shadeHit(m, *hit.part, ray_w, hit.t, p_w, n_w, uv, cos_i, view.pixel_angle), static_cast<float>(hit.t),
          static_cast<uint8_t>(hit.object + 1), static_cast<float>(cos_i)};
}

}  // namespace

RenderedLayer SceneModel::cast(const SE3& T_world_cam, double time_s, const CameraIntrinsics& camera) const {
  const int W = camera.width, H = camera.height;
  RenderedLayer out;
  out.color.create(H, W, CV_32FC3);
  out.depth_clean.create(H, W, CV_32F);
  out.object_id.create(H, W, CV_8U);
  out.cos_incidence.create(H, W, CV_32F);
  const std::vector<PosedObject> posed = posedObjects(objects, T_world_cam, time_s);

  // Screen-space culling: each item's bounds projected to a pixel rectangle (the whole image when
  // a corner is near or behind the camera); every tile of rows x columns tests only the items
  // whose rectangle overlaps it.
  const SE3 T_cam_world = T_world_cam.inverse();
  std::vector<cv::Rect2d> furniture_rect, object_rect;
  for (const Item& item : furniture) furniture_rect.push_back(screenRect(item, T_cam_world, camera));
  for (size_t k = 0; k < objects.size(); ++k)
    object_rect.push_back(
        screenRect(objects[k].shape, T_cam_world * objects[k].path->T_world_object(time_s), camera));
  constexpr int kTile = 16;
  const int tiles_x = (W + kTile - 1) / kTile, tiles_y = (H + kTile - 1) / kTile;

  cv::parallel_for_(cv::Range(0, tiles_y), [&](const cv::Range& tile_rows) {
    std::vector<const Item*> items;
    std::vector<int> objs;
    const TileView view{*this, posed, items, objs, T_world_cam.linear(), T_world_cam.translation(),
                        2.0 / (camera.fx + camera.fy)};
    for (int ty = tile_rows.start; ty < tile_rows.end; ++ty)
      for (int tx = 0; tx < tiles_x; ++tx) {
        const cv::Rect2d tile(tx * kTile, ty * kTile, kTile, kTile);
        items.clear();
        objs.clear();
        for (size_t i = 0; i < furniture.size(); ++i)
          if ((furniture_rect[i] & tile).area() > 0) items.push_back(&furniture[i]);
        for (size_t k = 0; k < objects.size(); ++k)
          if ((object_rect[k] & tile).area() > 0) objs.push_back(static_cast<int>(k));
        for (int v = ty * kTile; v < std::min(H, (ty + 1) * kTile); ++v)
          for (int u = tx * kTile; u < std::min(W, (tx + 1) * kTile); ++u) {
            const PixelSample p =
                castPixel(view, Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0));
            out.color.at<cv::Vec3f>(v, u) = p.color;
            out.depth_clean.at<float>(v, u) = p.depth;
            out.object_id.at<uint8_t>(v, u) = p.object_id;
            out.cos_incidence.at<float>(v, u) = p.cos_incidence;
          }
      }
  });
  return out;
}

cv::Mat finishColor(const cv::Mat& color_f, const RenderOptions& options) {
  cv::Mat blurred;
  if (options.psf_sigma_px > 0)
    cv::GaussianBlur(color_f, blurred, cv::Size(0, 0), options.psf_sigma_px, options.psf_sigma_px,
                     cv::BORDER_REPLICATE);
  else
    blurred = color_f;
  cv::Mat out(color_f.size(), CV_8UC3);
  const double sigma = options.noise ? options.color_noise : 0.0;
  cv::parallel_for_(cv::Range(0, color_f.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const cv::Vec3f* in = blurred.ptr<cv::Vec3f>(v);
      cv::Vec3b* o = out.ptr<cv::Vec3b>(v);
      for (int u = 0; u < color_f.cols; ++u)
        for (int c = 0; c < 3; ++c) {
          double x = in[u][c] * 255.0;
          if (sigma > 0)
            x += sigma * hashNormal(hashCombine(options.noise_key, (static_cast<uint64_t>(v) * color_f.cols + u) * 4 + c));
          o[u][c] = cv::saturate_cast<uint8_t>(x);
        }
    }
  });
  return out;
}

double depthNoiseSigma(double z_m) { return 0.0012 + 0.0019 * (z_m - 0.4) * (z_m - 0.4); }

cv::Mat kinectDepth(const cv::Mat& depth_clean, const cv::Mat& cos_incidence, const RenderOptions& options) {
  if (!options.noise) return depth_clean.clone();
  const int W = depth_clean.cols, H = depth_clean.rows;
  // Kinect v1: disparity in 1/8 pixel steps, focal length ~580 px, baseline ~7.5 cm, so depth
  // steps of z^2 / 348 m (3 mm at 1 m, 10 cm at 6 m).
  constexpr double kDisparityConstant = 580.0 * 0.075 * 8.0;
  // Kinect shadows: pixels whose neighbourhood holds a clearly nearer surface get no depth; always
  // within `shadow` pixels of the edge, often up to 2 * shadow on one side (the projector sits
  // beside the IR camera). Width scales with the image (1 px at 320, 2 px at 640).
  const int shadow = std::max(1, static_cast<int>(std::lround(W / 320.0)));
  cv::Mat z_far = depth_clean.clone(), near_min, wide_min;
  z_far.setTo(1e9f, depth_clean <= 0);
  if (options.depth_shadows) {
    cv::erode(z_far, near_min, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * shadow + 1, 3)));
    cv::erode(z_far, wide_min, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3 * shadow + 1, 3)),
              cv::Point(shadow, 1));
  }
  const uint64_t key = hashCombine(options.noise_key, 0x44455054ULL);
  cv::Mat out(H, W, CV_32F);
  cv::parallel_for_(cv::Range(0, H), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* z_in = depth_clean.ptr<float>(v);
      const float* c_in = cos_incidence.ptr<float>(v);
      float* z_out = out.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const double z = z_in[u];
        const uint64_t pk = hashCombine(key, static_cast<uint64_t>(v) * W + u);
        z_out[u] = 0;
        if (z <= 0 || z < options.min_depth || z > options.max_depth) continue;
        if (c_in[u] < 0.08 + 0.1 * hashUniform(pk ^ 1)) continue;  // grazing angles: no return
        if (hashUniform(pk ^ 2) < 0.002) continue;                  // sparse dropouts
        if (options.depth_shadows) {
          const double step = std::max(0.05, 0.03 * z);
          if (near_min.at<float>(v, u) < z - step) continue;
          if (wide_min.at<float>(v, u) < z - step && hashUniform(pk ^ 3) < 0.6) continue;
        }
        double zn = z + depthNoiseSigma(z) * hashNormal(pk ^ 7);
        zn = kDisparityConstant / std::round(kDisparityConstant / zn);
        zn = std::round(zn * 5000.0) / 5000.0;
        z_out[u] = static_cast<float>(zn);
      }
    }
  });
  return out;
}

}  // namespace ff::synth

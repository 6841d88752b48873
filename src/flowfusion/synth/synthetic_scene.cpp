#include "flowfusion/synth/synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <future>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/synth/people.h"
#include "flowfusion/synth/scene_model.h"

namespace ff::synth {

namespace {

constexpr double kDeg = M_PI / 180.0;
// Salts that split the seed into independent streams: the static twin (objects = 0) must get the
// same room and camera, whatever the objects draw.
constexpr uint64_t kRoomStream = 0x524f4f4dULL, kObjectStream = 0x4f424a53ULL, kNoiseStream = 0x4e4f4953ULL;
// Streams of the hard-case options, one each, so that none of them changes the others' draws.
constexpr uint64_t kRpyStream = 0x52505953ULL, kSeatStream = 0x53454154ULL, kPeopleStream = 0x50504c45ULL,
                   kNearStream = 0x4e454152ULL, kPushedStream = 0x50555348ULL, kLoopStream = 0x4c4f4f50ULL;

// Objects move back and forth on an arc around the room centre (so they cross the camera's view),
// with a slow radial wobble. People face where they walk and turn round smoothly at the ends.
class RingPath : public ObjectPath {
 public:
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius0 = 1.7, angle0 = 0, height = 0;
  Sinusoids radius, angle;  // m, rad
  bool faces_motion = false;
  Sinusoids spin;           // rad, for objects that do not face their motion
  double heading0 = 0;

  SE3 T_world_object(double t) const override {
    const double a = angle0 + angle.value(t), r = radius0 + radius.value(t);
    double heading = heading0 + spin.value(t);
    if (faces_motion) {
      const double rate = angle.derivative(t) / std::max(1e-9, angle.rmsDerivative());
      heading = a + 0.5 * M_PI * std::tanh(3.0 * rate);
    }
    SE3 T = SE3::Identity();
    T.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(centre.x() + r * std::cos(a), centre.y() + r * std::sin(a), height);
    return T;
  }
  double rmsSpeed() const {
    const double v_t = radius0 * angle.rmsDerivative(), v_r = radius.rmsDerivative();
    return std::sqrt(v_t * v_t + v_r * v_r);
  }
  nlohmann::json describe() const override {
    return {{"type", "ring"}, {"centre_m", {centre.x(), centre.y()}}, {"radius0_m", radius0},
            {"angle0_rad", angle0}, {"height_m", height}, {"radius_m", radius.describe()},
            {"angle_rad", angle.describe()}, {"faces_motion", faces_motion}, {"heading0_rad", heading0},
            {"spin_rad", spin.describe()}};
  }
};

// Furniture is built in a wall frame (s along the wall, n away from it, z up) and mapped to the
// world; `wall` 0..3 = the walls at x = 0, x = W, y = 0, y = D.
struct WallFrame {
  int wall;
  Eigen::Vector3d size;
  Eigen::Vector3d point(double s, double n, double z) const {
    switch (wall) {
      case 0: return {n, s, z};
      case 1: return {size.x() - n, s, z};
      case 2: return {s, n, z};
      default: return {s, size.y() - n, z};
    }
  }
  Part part(double s0, double s1, double n0, double n1, double z0, double z1, int texture, Rng& rng,
            float albedo = 1.0f) const {
    const Eigen::Vector3d a = point(s0, n0, z0), b = point(s1, n1, z1);
    return box(a.cwiseMin(b), a.cwiseMax(b), texture, rng, albedo);
  }
};

struct Palette {
  int wood, painted_a, painted_b, fabric, poster_a, poster_b, poster_c, dark;
};

void addTable(Item& it, const std::function<Part(double, double, double, double, double, double, int, float)>& mk,
              double s0, double w, double n0, double d, double h, int top_tex, int leg_tex) {
  const double leg = 0.05, top = 0.04;
  it.add(mk(s0, s0 + w, n0, n0 + d, h - top, h, top_tex, 1.0f));
  for (int i = 0; i < 4; ++i) {
    const double s = i % 2 ? s0 + w - leg - 0.03 : s0 + 0.03, n = i / 2 ? n0 + d - leg - 0.03 : n0 + 0.03;
    it.add(mk(s, s + leg, n, n + leg, 0, h - top, leg_tex, 0.8f));
  }
}

// Places furniture (and pictures above low pieces) along one wall between s_begin and s_end.
void furnishWall(SceneModel& m, Rng& rng, const WallFrame& f, double s_begin, double s_end, const Palette& pal) {
  double s = s_begin + rng.uniform(0.0, 0.6);
  const auto mk = [&](double s0, double s1, double n0, double n1, double z0, double z1, int tex, float albedo) {
    return f.part(s0, s1, n0, n1, z0, z1, tex, rng, albedo);
  };
  const double H = f.size.z();
  while (true) {
    const int kind = rng.uniformInt(0, 4);
    Item it;
    double w = 0, top = 0;  // width along the wall, height of the item's top
    if (kind == 0) {  // bookshelf: frame, boards and rows of books
      w = rng.uniform(0.7, 1.2);
      const double d = rng.uniform(0.3, 0.42), h = rng.uniform(1.6, 2.1), t = 0.02;
      if (s + w > s_end) break;
      const int tex = rng.chance(0.5) ? pal.wood : pal.painted_a;
      it.kind = "bookshelf";
      it.add(mk(s, s + w, 0, 0.02, 0, h, tex, 0.9f));
      it.add(mk(s, s + t, 0, d, 0, h, tex, 1.0f));
      it.add(mk(s + w - t, s + w, 0, d, 0, h, tex, 1.0f));
      const int boards = rng.uniformInt(4, 5);
      for (int b = 0; b <= boards; ++b) {
        const double z = b * (h - t) / boards;
        it.add(mk(s + t, s + w - t, 0.02, d, z, z + t, tex, 1.0f));
        if (b < boards && rng.chance(0.85)) {
          const double gap = (h - t) / boards - t;
          const double b0 = s + t + rng.uniform(0, 0.2 * w), b1 = s + w - t - rng.uniform(0, 0.2 * w);
          const int books = rng.chance(0.5) ? pal.poster_a : pal.poster_b;
          it.add(mk(b0, b1, 0.03, d - rng.uniform(0.03, 0.1), z + t, z + t + gap * rng.uniform(0.6, 0.9), books, 1.0f));
        }
      }
      top = h;
    } else if (kind == 1) {  // cabinet, sometimes with a box on top
      w = rng.uniform(0.6, 1.4);
      const double d = rng.uniform(0.4, 0.6), h = rng.uniform(0.7, 1.2);
      if (s + w > s_end) break;
      it.kind = "cabinet";
      it.add(mk(s, s + w, 0, d, 0, h, rng.chance(0.5) ? pal.painted_a : pal.painted_b, 1.0f));
      if (rng.chance(0.6)) {
        const double bw = rng.uniform(0.2, 0.4), bs = s + rng.uniform(0.05, w - bw - 0.05);
        it.add(mk(bs, bs + bw, 0.05, 0.05 + rng.uniform(0.2, 0.35), h, h + rng.uniform(0.15, 0.35), pal.poster_c, 1.0f));
      }
      top = h;
    } else if (kind == 2) {  // table or desk against the wall
      w = rng.uniform(1.0, 1.6);
      if (s + w > s_end) break;
      it.kind = "table";
      const double h = rng.uniform(0.72, 0.77);
      addTable(it, mk, s, w, 0.0, rng.uniform(0.6, 0.85), h, pal.wood, pal.dark);
      top = h;
    } else if (kind == 3) {  // sofa
      w = rng.uniform(1.6, 2.2);
      if (s + w > s_end) break;
      it.kind = "sofa";
      const double d = rng.uniform(0.8, 0.9);
      it.add(mk(s + 0.2, s + w - 0.2, 0.2, d, 0, 0.44, pal.fabric, 1.0f));
      it.add(mk(s, s + w, 0, 0.2, 0, 0.85, pal.fabric, 0.95f));
      it.add(mk(s, s + 0.2, 0, d, 0, 0.62, pal.fabric, 1.0f));
      it.add(mk(s + w - 0.2, s + w, 0, d, 0, 0.62, pal.fabric, 1.0f));
      top = 0.85;
    } else {  // free wall: only a picture
      w = rng.uniform(0.5, 1.2);
      if (s + w > s_end) break;
      top = 0.0;
    }
    if (top < 1.1 && rng.chance(0.75)) {  // picture above low furniture
      const double pw = std::min(w * rng.uniform(0.5, 0.9), 1.2), ph = rng.uniform(0.35, 0.8);
      const double ps = s + (w - pw) * rng.uniform(0.2, 0.8), pz = std::min(H - ph - 0.2, rng.uniform(1.25, 1.6));
      Item pic;
      pic.kind = "picture";
      const int tex = rng.chance(0.5) ? pal.poster_a : pal.poster_c;
      pic.add(mk(ps - 0.02, ps + pw + 0.02, 0, 0.025, pz - 0.02, pz + ph + 0.02, pal.dark, 1.0f));
      pic.add(mk(ps, ps + pw, 0.025, 0.03, pz, pz + ph, tex, 1.0f));
      m.furniture.push_back(pic);
    }
    if (!it.parts.empty()) m.furniture.push_back(it);
    s += w + rng.uniform(0.1, 0.8);
  }
}

// Scales the rotation's time so that its RMS angular speed is `deg_per_s`.
void scaleAngularSpeed(CameraPath& cam, double deg_per_s) {
  const double w2 = cam.yaw.rmsDerivative() * cam.yaw.rmsDerivative() +
                    cam.pitch.rmsDerivative() * cam.pitch.rmsDerivative() +
                    cam.roll.rmsDerivative() * cam.roll.rmsDerivative();
  const double k_r = deg_per_s * kDeg / std::sqrt(w2);
  cam.yaw.scaleTime(k_r);
  cam.pitch.scaleTime(k_r);
  cam.roll.scaleTime(k_r);
}

// The room's box with its textures into m.room, and the palette its furniture is made of.
Palette addRoomShell(SceneModel& m, Rng& rng) {
  Room room;
  room.size = Eigen::Vector3d(rng.uniform(6.5, 8.0), rng.uniform(6.5, 8.0), rng.uniform(2.6, 3.0));
  const int wall = m.addTexture(Material::Plaster, rng);
  const int accent = rng.chance(0.5) ? m.addTexture(Material::Plaster, rng) : wall;
  const int floor = m.addTexture(rng.chance(0.7) ? Material::Wood : Material::Fabric, rng);
  const int ceiling = m.addTexture(Material::Ceiling, rng);
  Palette pal{};
  pal.wood = m.addTexture(Material::Wood, rng);
  pal.painted_a = m.addTexture(Material::Painted, rng);
  pal.painted_b = m.addTexture(Material::Painted, rng);
  pal.fabric = m.addTexture(Material::Fabric, rng);
  pal.poster_a = m.addTexture(Material::Poster, rng);
  pal.poster_b = m.addTexture(Material::Poster, rng);
  pal.poster_c = m.addTexture(Material::Poster, rng);
  pal.dark = m.addTexture(Material::Painted, rng);
  const int accent_face = rng.uniformInt(0, 3);
  for (int f = 0; f < 6; ++f) {
    const int tex = f == 4 ? floor : f == 5 ? ceiling : (f == accent_face ? accent : wall);
    room.faces[f] = box(Eigen::Vector3d::Zero(), room.size, tex, rng);
  }
  m.room = room;
  return pal;
}

// A handheld camera path about the room's centre, at the configured RMS speeds.
CameraPath handheldPath(Rng& rng, const Eigen::Vector3d& room_size, const SynthConfig& cfg) {
  CameraPath cam;
  cam.centre = Eigen::Vector3d(room_size.x() / 2, room_size.y() / 2, rng.uniform(1.35, 1.55));
  cam.yaw0 = rng.uniform(0, 2 * M_PI);
  cam.pitch0 = -rng.uniform(4, 12) * kDeg;
  cam.position[0] = randomSinusoids(rng, {{0.25, 0.07}, {0.12, 0.15}, {0.05, 0.3}});
  cam.position[1] = randomSinusoids(rng, {{0.25, 0.07}, {0.12, 0.15}, {0.05, 0.3}});
  cam.position[2] = randomSinusoids(rng, {{0.08, 0.1}, {0.04, 0.25}});
  cam.yaw = randomSinusoids(rng, {{40 * kDeg, 0.05}, {12 * kDeg, 0.15}, {4 * kDeg, 0.4}});
  cam.pitch = randomSinusoids(rng, {{6 * kDeg, 0.08}, {3 * kDeg, 0.25}});
  cam.roll = randomSinusoids(rng, {{3 * kDeg, 0.1}, {1.5 * kDeg, 0.3}});
  double v2 = 0;
  for (const auto& p : cam.position) v2 += p.rmsDerivative() * p.rmsDerivative();
  const double k_t = cfg.camera_speed / std::sqrt(v2);
  for (auto& p : cam.position) p.scaleTime(k_t);
  scaleAngularSpeed(cam, cfg.camera_angular_speed);
  return cam;
}

// Free-standing furniture between the camera and the objects' paths, near the initial view
// direction, so that objects are also occluded: a coffee table and a floor lamp.
void addFreeStanding(SceneModel& m, Rng& rng, const CameraPath& cam, const Palette& pal) {
  const Eigen::Vector3d& room_size = m.room->size;
  const Eigen::Vector2d c2(cam.centre.x(), cam.centre.y());
  {
    const double a = cam.yaw0 + rng.uniform(-0.6, -0.2), r = rng.uniform(1.05, 1.15);
    const double w = rng.uniform(0.7, 1.0), d = rng.uniform(0.45, 0.6), h = rng.uniform(0.4, 0.5);
    const Eigen::Vector2d p = c2 + r * Eigen::Vector2d(std::cos(a), std::sin(a));
    Item it;
    it.kind = "coffee_table";
    // Axis-aligned; its half-diagonal (< 0.6 m) keeps it clear of the camera's excursions.
    const WallFrame world{2, room_size};  // s = x, n = y
    addTable(it, [&](double s0, double s1, double n0, double n1, double z0, double z1, int tex, float al) {
               return world.part(s0, s1, n0, n1, z0, z1, tex, rng, al);
             },
             p.x() - w / 2, w, p.y() - d / 2, d, h, pal.painted_b, pal.dark);
    m.furniture.push_back(it);
  }
  const double a = cam.yaw0 + rng.uniform(0.25, 0.6), r = rng.uniform(1.1, 1.2);
  const Eigen::Vector2d p = c2 + r * Eigen::Vector2d(std::cos(a), std::sin(a));
  const double h = rng.uniform(1.5, 1.75);
  Item it;
  it.kind = "floor_lamp";
  it.add(box(Eigen::Vector3d(p.x() - 0.15, p.y() - 0.15, 0), Eigen::Vector3d(p.x() + 0.15, p.y() + 0.15, 0.03),
             pal.dark, rng));
  it.add(box(Eigen::Vector3d(p.x() - 0.02, p.y() - 0.02, 0.03), Eigen::Vector3d(p.x() + 0.02, p.y() + 0.02, h),
             pal.dark, rng));
  it.add(box(Eigen::Vector3d(p.x() - 0.17, p.y() - 0.17, h), Eigen::Vector3d(p.x() + 0.17, p.y() + 0.17, h + 0.3),
             pal.fabric, rng, 1.3f));
  m.furniture.push_back(it);
}

// The room, its furniture, the light and the camera path: everything of the static twin.
CameraPath buildRoom(SceneModel& m, Rng& rng, const SynthConfig& cfg) {
  const Palette pal = addRoomShell(m, rng);
  const Eigen::Vector3d room_size = m.room->size;
  for (int w = 0; w < 4; ++w) {
    const WallFrame f{w, room_size};
    const double len = w < 2 ? room_size.y() : room_size.x();
    // Walls 2 and 3 leave the corners to walls 0 and 1.
    const double margin = w < 2 ? 0.1 : 1.0;
    furnishWall(m, rng, f, margin, len - margin, pal);
  }
  const CameraPath cam = handheldPath(rng, room_size, cfg);
  // Not on a loop, which passes where it would stand.
  if (cfg.camera_path == CameraPathKind::Sweep) addFreeStanding(m, rng, cam, pal);
  m.light.position = Eigen::Vector3d(room_size.x() / 2 + rng.uniform(-1, 1), room_size.y() / 2 + rng.uniform(-1, 1),
                                     room_size.z() - 0.4);
  return cam;
}

void addObjects(SceneModel& m, Rng& rng, const SynthConfig& cfg, const CameraPath& cam) {
  for (int k = 0; k < cfg.objects; ++k) {
    MovingObject obj;
    const bool person = k == 0 || rng.chance(0.6);
    obj.shape = person ? personShape(m, rng) : boxShape(m, rng, 0.35, 0.7);
    auto path = std::make_shared<RingPath>();
    path->centre = Eigen::Vector2d(cam.centre.x(), cam.centre.y());
    path->radius0 = rng.uniform(1.6, 1.9);
    path->angle0 = cam.yaw0 + rng.uniform(-0.5, 0.5);
    path->angle = randomSinusoids(rng, {{rng.uniform(0.5, 0.9), 0.07}, {0.1, 0.2}});
    path->radius = randomSinusoids(rng, {{0.08, 0.15}});
    path->faces_motion = person;
    path->heading0 = rng.uniform(0, 2 * M_PI);
    if (!person) {
      path->spin = randomSinusoids(rng, {{rng.uniform(0.3, 1.0), 0.1}});
      if (rng.chance(0.4)) path->height = rng.uniform(0.5, 0.9);  // carried
    }
    const double k_t = cfg.object_speed / std::max(1e-9, path->rmsSpeed());
    path->angle.scaleTime(k_t);
    path->radius.scaleTime(k_t);
    path->spin.scaleTime(k_t);
    obj.path = path;
    m.objects.push_back(std::move(obj));
  }
}

// Rotation about all three axes at similar amplitudes (+-15-20 degrees, 0.3-0.9 Hz), scaled to the
// configured RMS angular speed; the translation stays the hand-held one.
void makeRpy(CameraPath& cam, const SynthConfig& cfg) {
  Rng rng(hashCombine(cfg.seed, kRpyStream));
  cam.yaw = randomSinusoids(rng, {{18 * kDeg, 0.3}, {6 * kDeg, 0.7}});
  cam.pitch = randomSinusoids(rng, {{14 * kDeg, 0.35}, {5 * kDeg, 0.8}});
  cam.roll = randomSinusoids(rng, {{14 * kDeg, 0.4}, {5 * kDeg, 0.9}});
  scaleAngularSpeed(cam, cfg.camera_angular_speed);
}

// Round the room's centre at the configured speed, looking outwards, with a small hand-held wobble
// of position (a few cm) and angles (a few degrees) that is not scaled with the speed.
void makeLoop(CameraPath& cam, const SynthConfig& cfg) {
  Rng rng(hashCombine(cfg.path_seed != 0 ? cfg.path_seed : cfg.seed, kLoopStream));
  cam.loop_radius_m = kLoopRadiusM;
  cam.loop_rate = cfg.camera_speed / kLoopRadiusM;
  cam.position[0] = randomSinusoids(rng, {{0.03, 0.2}, {0.01, 0.5}});
  cam.position[1] = randomSinusoids(rng, {{0.03, 0.2}, {0.01, 0.5}});
  cam.position[2] = randomSinusoids(rng, {{0.03, 0.15}});
  cam.yaw = randomSinusoids(rng, {{5 * kDeg, 0.15}, {1.5 * kDeg, 0.4}});
  cam.pitch = randomSinusoids(rng, {{3 * kDeg, 0.2}});
  cam.roll = randomSinusoids(rng, {{2 * kDeg, 0.25}});
}

// The first camera's view as seen on the floor: where people walk, seats and pushed objects stand.
WalkLine firstView(const CameraPath& cam) {
  const SE3 T = cam.T_world_cam(0.0);
  WalkLine line;
  line.eye = T.translation().head<2>();
  const Eigen::Vector2d v = T.linear().col(2).head<2>();
  line.view = v.norm() > 1e-6 ? Eigen::Vector2d(v.normalized()) : Eigen::Vector2d::UnitX();
  return line;
}

struct Seat {
  Eigen::Vector2d centre;
  double height;
};

std::vector<Seat> addSeats(SceneModel& m, const SynthConfig& cfg, const WalkLine& view) {
  Rng rng(hashCombine(cfg.seed, kSeatStream));
  std::vector<Seat> seats;
  for (int k = 0; k < cfg.seats; ++k) {
    const double lateral = (k - 0.5 * (cfg.seats - 1)) * 1.1 + rng.uniform(-0.2, 0.2);
    WalkLine line = view;
    line.distance_m = rng.uniform(1.9, 2.3);
    const Seat seat{line.point(lateral), rng.uniform(0.42, 0.47)};
    const int tex = m.addTexture(rng.chance(0.5) ? Material::Cardboard : Material::Painted, rng);
    Item it;
    it.kind = "seat";
    it.add(box(Eigen::Vector3d(seat.centre.x() - 0.21, seat.centre.y() - 0.21, 0),
               Eigen::Vector3d(seat.centre.x() + 0.21, seat.centre.y() + 0.21, seat.height), tex, rng));
    m.furniture.push_back(it);
    seats.push_back(seat);
  }
  return seats;
}

std::vector<std::shared_ptr<const Body>> addPeople(SceneModel& m, const SynthConfig& cfg, const WalkLine& view,
                                                   const std::vector<Seat>& seats) {
  Rng rng(hashCombine(cfg.seed, kPeopleStream));
  const double t_end = cfg.frames / cfg.fps + 1.0;
  std::vector<std::shared_ptr<const Body>> people;
  for (int k = 0; k < cfg.people; ++k) {
    WalkLine line = view;
    std::shared_ptr<const Body> body;
    if (k < static_cast<int>(seats.size())) {
      line.distance_m = (seats[k].centre - view.eye).dot(view.view) - 0.38;
      // Started 2-2.5 s early, so that the first sitting down falls in the first seconds.
      body = sitterScript(rng, line, seats[k].centre, seats[k].height, -rng.uniform(2.0, 2.5), t_end);
    } else {
      line.distance_m = rng.uniform(1.7, 2.4);
      line.half_m = rng.uniform(1.1, 1.5);
      body = walkerScript(rng, line, -rng.uniform(0.0, 1.5), t_end);
    }
    for (MovingObject& o : personObjects(m, rng, body, k)) m.objects.push_back(std::move(o));
    people.push_back(body);
  }
  return people;
}

void addNearObjects(SceneModel& m, const SynthConfig& cfg, const CameraPath& cam, const CameraIntrinsics& K) {
  Rng rng(hashCombine(cfg.seed, kNearStream));
  const double tan_x = 0.5 * K.width / K.fx, tan_y = 0.5 * K.height / K.fy;
  for (int k = 0; k < cfg.near_objects; ++k) {
    MovingObject obj;
    obj.shape = centred(boxShape(m, rng, 0.45, 0.65));
    obj.shape.kind = "near_box";
    obj.path = crossingPath(rng, cam.T_world_cam(0.0), tan_x, tan_y, 1.0, 1.5, cfg.object_speed);
    m.objects.push_back(std::move(obj));
  }
}

void addPushedObjects(SceneModel& m, const SynthConfig& cfg, const WalkLine& view) {
  Rng rng(hashCombine(cfg.seed, kPushedStream));
  for (int k = 0; k < cfg.pushed_objects; ++k) {
    MovingObject obj;
    obj.shape = rng.chance(0.6) ? chairShape(m, rng) : boxShape(m, rng, 0.4, 0.6);
    WalkLine line = view;
    line.distance_m = rng.uniform(1.4, 2.2);
    auto path = std::make_shared<PushedPath>();
    const Eigen::Vector2d at = line.point(rng.uniform(-0.6, 0.6));
    path->base.translation() = Eigen::Vector3d(at.x(), at.y(), 0);
    path->base.linear() = Eigen::AngleAxisd(rng.uniform(0, 2 * M_PI), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    // One draw per statement, so that the sequence of draws does not depend on the compiler.
    const double towards = rng.uniform(-0.2, 0.2);
    const double side = rng.sign();
    const double across = rng.uniform(0.6, 1.0);
    const Eigen::Vector2d push = side * across * line.lateral() + towards * line.view;
    path->push = Eigen::Vector3d(push.x(), push.y(), 0);
    path->rest_s = cfg.rest_s;
    path->push_s = rng.uniform(1.2, 1.8);
    path->spin_rad = rng.uniform(-0.4, 0.4);
    obj.path = path;
    m.objects.push_back(std::move(obj));
  }
}

CameraIntrinsics scaledFr1(int width, int height) {
  CameraIntrinsics c = *freiburgPreset(1);
  const double sx = width / 640.0, sy = height / 480.0;
  // Pixel centres sit at integer coordinates, so the principal point scales about -0.5.
  c.fx *= sx;
  c.fy *= sy;
  c.cx = (c.cx + 0.5) * sx - 0.5;
  c.cy = (c.cy + 0.5) * sy - 0.5;
  c.width = width;
  c.height = height;
  return c;
}

void validate(const SynthConfig& c) {
  const auto bad = [](const std::string& what) { throw InputError("synth configuration: " + what); };
  if (c.frames < 1) bad("frames must be >= 1, got " + std::to_string(c.frames));
  if (c.objects < 0 || c.objects > 32) bad("objects must be in 0..32, got " + std::to_string(c.objects));
  if (c.width < 16 || c.height < 16 || c.width > 4096 || c.height > 4096)
    bad("image size must be 16..4096 pixels, got " + std::to_string(c.width) + "x" + std::to_string(c.height));
  if (!(c.fps > 0 && c.fps <= 1000)) bad("fps must be in (0, 1000], got " + std::to_string(c.fps));
  if (!(c.camera_speed >= 0 && c.camera_speed <= 5)) bad("camera_speed must be in [0, 5] m/s");
  if (!(c.camera_angular_speed >= 0 && c.camera_angular_speed <= 360))
    bad("camera_angular_speed must be in [0, 360] deg/s");
  if (!(c.object_speed >= 0 && c.object_speed <= 5)) bad("object_speed must be in [0, 5] m/s");
  if (!(c.min_depth >= 0 && c.max_depth > c.min_depth && c.max_depth <= 13))
    bad("need 0 <= min_depth < max_depth <= 13 m (16-bit PNG at 5000/m)");
  if (!(c.color_noise >= 0 && c.color_noise <= 50)) bad("color_noise must be in [0, 50] levels");
  if (!std::isfinite(c.start_time) || c.start_time < 0) bad("start_time must be >= 0 s");
  if (c.people < 0 || c.people > 8) bad("people must be in 0..8, got " + std::to_string(c.people));
  if (c.seats < 0 || c.seats > 4) bad("seats must be in 0..4, got " + std::to_string(c.seats));
  if (c.near_objects < 0 || c.near_objects > 4)
    bad("near_objects must be in 0..4, got " + std::to_string(c.near_objects));
  if (c.pushed_objects < 0 || c.pushed_objects > 4)
    bad("pushed_objects must be in 0..4, got " + std::to_string(c.pushed_objects));
  if (!(c.rest_s >= 0 && c.rest_s <= 600)) bad("rest_s must be in [0, 600] s");
  if (!(c.exposure_ms >= 0 && c.exposure_ms <= 200)) bad("exposure_ms must be in [0, 200] ms");
  if (!(c.cover_at_s >= 0 && c.cover_s >= 0 && std::isfinite(c.cover_at_s + c.cover_s)))
    bad("cover_at_s and cover_s must be >= 0 s");
  if (c.laps < 0 || c.laps > 100) bad("laps must be in 0..100, got " + std::to_string(c.laps));
  if (c.laps > 0 && c.camera_path != CameraPathKind::Loop) bad("laps needs camera_path loop");
  if (!std::isfinite(c.path_start_s) || c.path_start_s < 0) bad("path_start_s must be >= 0 s");
  if (c.path_seed != 0 && c.camera_path != CameraPathKind::Loop) bad("path_seed needs camera_path loop");
  if (c.camera_path == CameraPathKind::Loop && c.camera_motion != CameraMotion::Handheld)
    bad("camera_path loop takes camera_motion handheld");
  if (c.camera_path == CameraPathKind::Loop && !(c.camera_speed > 0)) bad("camera_path loop needs camera_speed > 0");
  if (c.exposure_samples < 2 || c.exposure_samples > 64)
    bad("exposure_samples must be in 2..64, got " + std::to_string(c.exposure_samples));
}

}  // namespace

int frameCount(const SynthConfig& c) {
  if (c.laps <= 0 || !(c.camera_speed > 0)) return c.frames;
  const double frames = std::round(c.laps * 2 * M_PI * kLoopRadiusM / c.camera_speed * c.fps);
  return frames < 1e9 ? static_cast<int>(frames) : 1000000000;
}

SyntheticScene::SyntheticScene(const SynthConfig& config)
    : config_(config), camera_(), model_(std::make_unique<SceneModel>()) {
  validate(config_);
  config_.frames = synth::frameCount(config_);
  camera_ = scaledFr1(config_.width, config_.height);
  Rng room_rng(hashCombine(config_.seed, kRoomStream));
  CameraPath cam = buildRoom(*model_, room_rng, config_);
  if (config_.camera_motion == CameraMotion::Rpy) makeRpy(cam, config_);
  if (config_.camera_path == CameraPathKind::Loop) makeLoop(cam, config_);
  cam.start_s = config_.path_start_s;
  Rng object_rng(hashCombine(config_.seed, kObjectStream));
  addObjects(*model_, object_rng, config_, cam);
  const WalkLine view = firstView(cam);
  const std::vector<Seat> seats = addSeats(*model_, config_, view);
  first_person_object_ = objectCount();
  people_ = addPeople(*model_, config_, view, seats);
  addNearObjects(*model_, config_, cam, camera_);
  addPushedObjects(*model_, config_, view);
  camera_path_ = std::make_shared<CameraPath>(cam);
}

SyntheticScene::~SyntheticScene() = default;
SyntheticScene::SyntheticScene(SyntheticScene&&) noexcept = default;
SyntheticScene& SyntheticScene::operator=(SyntheticScene&&) noexcept = default;

double SyntheticScene::timestamp(int i) const { return config_.start_time + i / config_.fps; }

SE3 SyntheticScene::cameraPoseAt(double time_s) const {
  return camera_path_->T_world_cam(time_s - config_.start_time);
}

SE3 SyntheticScene::cameraPose(int i) const { return cameraPoseAt(timestamp(i)); }

int SyntheticScene::objectCount() const { return static_cast<int>(model_->objects.size()); }

SE3 SyntheticScene::objectPose(int k, double time_s) const {
  return model_->objects.at(k).path->T_world_object(time_s - config_.start_time);
}

SynthFrame SyntheticScene::render(int i) const {
  SynthFrame f = renderAt(cameraPose(i), timestamp(i));
  const double t = timestamp(i) - config_.start_time;
  if (config_.cover_s > 0 && t >= config_.cover_at_s && t < config_.cover_at_s + config_.cover_s) {
    for (cv::Mat* m : {&f.frame.color, &f.frame.intensity, &f.frame.depth, &f.mask, &f.object_id, &f.depth_clean})
      m->setTo(0);
  }
  return f;
}

SynthFrame SyntheticScene::renderAt(const SE3& T_world_cam, double time_s) const {
  RenderOptions opt;
  opt.camera = camera_;
  opt.noise = config_.noise;
  opt.min_depth = config_.min_depth;
  opt.max_depth = config_.max_depth;
  opt.color_noise = config_.color_noise;
  opt.noise_key = hashCombine(hashCombine(config_.seed, kNoiseStream),
                              static_cast<uint64_t>(std::llround(time_s * 1e6)));
  const double t = time_s - config_.start_time;
  const RenderedLayer layer = model_->cast(T_world_cam, t, camera_);
  SynthFrame out;
  out.T_world_cam = T_world_cam;
  out.frame.timestamp = time_s;
  out.frame.color = finishColor(config_.exposure_ms > 0 ? exposureColor(T_world_cam, t) : layer.color, opt);
  out.frame.intensity = intensityFromBgr(out.frame.color);
  out.frame.depth = kinectDepth(layer.depth_clean, layer.cos_incidence, opt);
  out.frame.name = "synth:" + timestampName(time_s);
  out.object_id = layer.object_id;
  out.mask = layer.object_id > 0;
  out.depth_clean = layer.depth_clean;
  return out;
}

cv::Mat SyntheticScene::exposureColor(const SE3& T_world_cam, double t) const {
  // The camera moves during the exposure as along its path, relative to the requested pose.
  const SE3 T_path_inv = camera_path_->T_world_cam(t).inverse();
  const int n = config_.exposure_samples;
  cv::Mat sum(camera_.height, camera_.width, CV_32FC3, cv::Scalar::all(0));
  for (int s = 0; s < n; ++s) {
    const double ts = t + 1e-3 * config_.exposure_ms * ((s + 0.5) / n - 0.5);
    sum += model_->cast(T_world_cam * (T_path_inv * camera_path_->T_world_cam(ts)), ts, camera_).color;
  }
  return sum * (1.0 / n);
}

std::shared_ptr<const Body> SyntheticScene::person(int k) const { return people_.at(k); }

nlohmann::json SyntheticScene::description() const {
  nlohmann::json j;
  j["generator"] = "flowfusion synth";
  j["generator_version"] = kGeneratorVersion;
  j["seed"] = config_.seed;
  j["config"] = config_;
  j["camera"] = {{"fx", camera_.fx}, {"fy", camera_.fy}, {"cx", camera_.cx}, {"cy", camera_.cy},
                 {"width", camera_.width}, {"height", camera_.height}};
  j["world_frame"] = "metres, z up, room spans [0, size]";
  j["room"] = {{"size_m", jsonVec(model_->room->size)}, {"light_m", jsonVec(model_->light.position)}};
  j["textures"] = model_->texture_names;
  j["camera_path"] = camera_path_->describe();
  j["furniture"] = nlohmann::json::array();
  for (const Item& it : model_->furniture) j["furniture"].push_back(it.describe());
  j["people"] = nlohmann::json::array();
  for (const auto& body : people_) j["people"].push_back(body->describe());
  j["first_person_object"] = first_person_object_;
  j["objects"] = nlohmann::json::array();
  for (const MovingObject& o : model_->objects) {
    nlohmann::json oj = o.shape.describe();
    oj["size_m"] = jsonVec(o.shape.hi - o.shape.lo);
    oj["path"] = o.path->describe();
    j["objects"].push_back(oj);
  }
  return j;
}

void writeSequence(const SyntheticScene& scene, const std::string& out_dir, bool overwrite) {
  prepareOutputDir(out_dir, overwrite);
  TumWriter writer(out_dir, scene.camera());
  // Frames are rendered a batch at a time in parallel (each render's own row loop then runs
  // serially inside its worker); PNG encoding of one batch overlaps the rendering of the next.
  const int batch = 8;
  std::future<void> writing;
  for (int first = 0; first < scene.frameCount(); first += batch) {
    const int n = std::min(batch, scene.frameCount() - first);
    auto frames = std::make_shared<std::vector<SynthFrame>>(n);
    cv::parallel_for_(cv::Range(0, n), [&](const cv::Range& r) {
      for (int i = r.start; i < r.end; ++i) (*frames)[i] = scene.render(first + i);
    });
    if (writing.valid()) writing.get();
    writing = std::async(std::launch::async, [&writer, frames] {
      for (const SynthFrame& f : *frames)
        writer.add(f.frame.timestamp, f.frame.color, f.frame.depth, f.T_world_cam, f.mask);
    });
  }
  writing.get();
  writer.finish("flowfusion synth, seed " + std::to_string(scene.config().seed) + ", generator version " +
                std::to_string(kGeneratorVersion));
  writeJsonFile((std::filesystem::path(out_dir) / "scene.json").string(), scene.description());
}

}  // namespace ff::synth

#include "flowfusion/synth/people.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace ff::synth {

namespace {

// Signed angle from heading a to heading b, in (-pi, pi].
double angleTo(double a, double b) {
  double d = std::remainder(b - a, 2 * M_PI);
  if (d <= -M_PI) d += 2 * M_PI;
  return d;
}

double headingOf(const Eigen::Vector2d& v) { return std::atan2(v.y(), v.x()); }

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

}  // namespace

std::vector<MovingObject> personObjects(SceneModel& m, Rng& rng, const std::shared_ptr<const Body>& body,
                                        int person) {
  const int trousers = m.addTexture(Material::Clothing, rng), shirt = m.addTexture(Material::Clothing, rng);
  const int skin = m.addTexture(Material::Skin, rng), hair = m.addTexture(Material::Fabric, rng);
  const int shoes = m.addTexture(Material::Fabric, rng);
  std::vector<MovingObject> out;
  for (int k = 0; k < kBodyParts; ++k) {
    const auto part = static_cast<BodyPart>(k);
    MovingObject obj;
    obj.shape.kind = std::string("person.") + bodyPartName(part);
    for (const Body::Box& b : body->partBoxes(part)) {
      int tex = skin;
      float albedo = 1.0f;
      switch (b.material) {
        case Body::Material::Trousers: tex = trousers; break;
        case Body::Material::Shirt: tex = shirt; break;
        case Body::Material::Skin: tex = skin; break;
        case Body::Material::Hair:
          tex = hair;
          albedo = 0.5f;
          break;
        case Body::Material::Shoes:
          tex = shoes;
          albedo = 0.35f;
          break;
      }
      obj.shape.add(box(b.lo, b.hi, tex, rng, albedo));
    }
    obj.path = std::make_shared<BodyPartPath>(body, part, person);
    out.push_back(std::move(obj));
  }
  return out;
}

Eigen::Vector2d WalkLine::lateral() const { return {-view.y(), view.x()}; }
Eigen::Vector2d WalkLine::point(double lateral_m) const { return eye + distance_m * view + lateral_m * lateral(); }

std::shared_ptr<Body> walkerScript(Rng& rng, const WalkLine& line, double t0, double t_end,
                                   const SE3& T_world_floor) {
  BodyDimensions dims;
  dims.scale = rng.uniform(0.92, 1.08);
  const double dir = rng.sign();
  const double length = 2 * line.half_m;
  // Start somewhere along the line, walking towards its far end.
  const double start = -dir * line.half_m * rng.uniform(0.3, 1.0);
  const FloorPose pose{line.point(start), headingOf(dir * line.lateral())};
  auto body = std::make_shared<Body>(dims, pose, t0, T_world_floor);
  // One draw per statement, so that the sequence of draws does not depend on the compiler.
  const double bend = rng.uniform(0.0, 0.15);
  const double curvature = bend * rng.sign();
  bool first = true;
  for (int leg = 0; body->endTime() < t_end; ++leg) {
    const double remaining = first ? std::fabs(dir * line.half_m - start) : length;
    first = false;
    body->walk(remaining, rng.uniform(0.5, 1.5), leg % 2 ? -curvature : curvature);
    if (rng.chance(0.5)) body->stand(rng.uniform(0.5, 2.0));
    body->turn(rng.sign() * M_PI);
  }
  return body;
}

std::shared_ptr<Body> sitterScript(Rng& rng, const WalkLine& line, const Eigen::Vector2d& seat_centre,
                                   double seat_height_m, double t0, double t_end) {
  BodyDimensions dims;
  dims.scale = rng.uniform(0.95, 1.05);
  // The feet stand 0.38 m in front of the seat's centre (towards the camera) and the pelvis moves
  // back 0.3 m onto the seat's front half.
  const Eigen::Vector2d towards_camera = -line.view;
  const Eigen::Vector2d spot = seat_centre + 0.38 * towards_camera;
  const double side = rng.sign(), away = rng.uniform(0.8, 1.2);
  const FloorPose pose{spot + side * away * line.lateral(), headingOf(-side * line.lateral())};
  auto body = std::make_shared<Body>(dims, pose, t0);
  const double speed = rng.uniform(0.6, 1.2);
  body->walk(away, speed);
  while (body->endTime() < t_end) {
    body->turn(angleTo(body->pose().heading, headingOf(towards_camera)));
    const double up_s = rng.uniform(1.0, 1.4);
    const double hold_s = rng.uniform(1.5, 3.0);
    const double down_s = rng.uniform(1.0, 1.4);
    body->sit(seat_height_m, 0.3, down_s, hold_s, up_s);
    const double leave = rng.sign();
    body->turn(angleTo(body->pose().heading, headingOf(leave * line.lateral())));
    body->walk(away, speed);
    if (rng.chance(0.5)) body->stand(rng.uniform(0.5, 1.5));
    body->turn(rng.sign() * M_PI);
    body->walk(away, speed);
  }
  return body;
}

Item chairShape(SceneModel& m, Rng& rng) {
  const int wood = m.addTexture(rng.chance(0.5) ? Material::Wood : Material::Painted, rng);
  const int cushion = m.addTexture(Material::Fabric, rng);
  const double w = rng.uniform(0.4, 0.48), h = rng.uniform(0.42, 0.48), back = rng.uniform(0.4, 0.5);
  const double leg = 0.04, seat = 0.05;
  Item it;
  it.kind = "chair";
  it.add(box(Eigen::Vector3d(-w / 2, -w / 2, h - seat), Eigen::Vector3d(w / 2, w / 2, h), cushion, rng));
  for (int i = 0; i < 4; ++i) {
    const double x = i % 2 ? w / 2 - leg : -w / 2, y = i / 2 ? w / 2 - leg : -w / 2;
    it.add(box(Eigen::Vector3d(x, y, 0), Eigen::Vector3d(x + leg, y + leg, h - seat), wood, rng, 0.8f));
  }
  it.add(box(Eigen::Vector3d(-w / 2, -w / 2, h), Eigen::Vector3d(-w / 2 + 0.04, w / 2, h + back), wood, rng));
  return it;
}

SE3 PushedPath::T_world_object(double t) const {
  const double period = 2 * (rest_s + push_s);
  double phase = 0;
  if (t > rest_s) {
    const double c = std::fmod(t, period);
    if (c < rest_s) phase = 0;
    else if (c < rest_s + push_s) phase = smoothstep((c - rest_s) / push_s);
    else if (c < 2 * rest_s + push_s) phase = 1;
    else phase = 1 - smoothstep((c - 2 * rest_s - push_s) / push_s);
  }
  SE3 T = base;
  T.translation() += phase * push;
  T.linear() = Eigen::AngleAxisd(phase * spin_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * base.linear();
  return T;
}

nlohmann::json PushedPath::describe() const {
  return {{"type", "rest_then_push"}, {"base_m", jsonVec(base.translation())}, {"push_m", jsonVec(push)},
          {"rest_s", rest_s}, {"push_s", push_s}, {"spin_rad", spin_rad}};
}

nlohmann::json BodyPartPath::describe() const {
  return {{"type", "body_part"}, {"person", person_}, {"part", bodyPartName(part_)}};
}

}  // namespace ff::synth

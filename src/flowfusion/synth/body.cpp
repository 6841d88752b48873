#include "flowfusion/synth/body.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace ff::synth {

namespace {

constexpr double kSampleStep = 0.005;  // s between pelvis samples
constexpr double kSwingSeconds = 0.45;  // one foot step of a turn on the spot

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

FloorPose lerp(const FloorPose& a, const FloorPose& b, double w) {
  return {a.p + w * (b.p - a.p), a.heading + w * (b.heading - a.heading)};
}

Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
Eigen::Matrix3d rotY(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

SE3 makePose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  SE3 T = SE3::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

// Frame of a limb segment from its proximal joint to its distal joint: origin at the proximal joint,
// z from the distal joint towards the proximal one, x as close to `forward` as z allows.
SE3 limbFrame(const Eigen::Vector3d& proximal, const Eigen::Vector3d& distal, const Eigen::Vector3d& forward) {
  const Eigen::Vector3d z = (proximal - distal).normalized();
  const Eigen::Vector3d x = (forward - forward.dot(z) * z).normalized();
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = z.cross(x);
  R.col(2) = z;
  return makePose(R, proximal);
}

// Knee position of a two-link leg from hip to ankle, bending towards `forward`.
Eigen::Vector3d kneePosition(const Eigen::Vector3d& hip, const Eigen::Vector3d& ankle, double a, double b,
                             const Eigen::Vector3d& forward) {
  const Eigen::Vector3d hv = ankle - hip;
  const double d = std::clamp(hv.norm(), std::fabs(a - b) + 1e-6, (a + b) * (1 - 1e-9));
  const Eigen::Vector3d u = hv.normalized();
  const Eigen::Vector3d f = (forward - forward.dot(u) * u).normalized();
  const double cos_a = std::clamp((a * a + d * d - b * b) / (2 * a * d), -1.0, 1.0);
  return hip + a * (cos_a * u + std::sqrt(1 - cos_a * cos_a) * f);
}

}  // namespace

Eigen::Vector2d FloorPose::forward() const { return {std::cos(heading), std::sin(heading)}; }
Eigen::Vector2d FloorPose::left() const { return {-std::sin(heading), std::cos(heading)}; }

const char* bodyPartName(BodyPart part) {
  static const char* names[] = {"pelvis",    "torso",       "upper_arm_left", "forearm_left",
                                "upper_arm_right", "forearm_right", "thigh_left", "shin_left",
                                "foot_left", "thigh_right", "shin_right",     "foot_right"};
  return names[static_cast<int>(part)];
}

Body::Body(const BodyDimensions& dims, const FloorPose& start, double t0, const SE3& T_world_floor)
    : dims_(dims), T_world_floor_(T_world_floor), t0_(t0), t_end_(t0), current_(start) {
  for (int side = 0; side < 2; ++side) foot_start_[side] = footprint(start, side);
  foot_now_ = foot_start_;
  addPelvis(t0, start);
}

FloorPose Body::footprint(const FloorPose& pelvis, int side) const {
  const double sign = side == 0 ? 1.0 : -1.0;
  return {pelvis.p + sign * 0.5 * dims_.foot_width() * pelvis.left(), pelvis.heading};
}

void Body::addPelvis(double t, const FloorPose& pose, double sit, double seat_height) {
  pelvis_.push_back({t, pose, sit, seat_height});
}

void Body::addSwing(int side, double t0, double t1, const FloorPose& to, double lift) {
  swings_[side].push_back({t0, t1, foot_now_[side], to, lift});
  foot_now_[side] = to;
}

void Body::walk(double distance_m, double speed_mps, double curvature_per_m) {
  const double nominal_step = std::min(0.8, 0.45 + 0.25 * speed_mps) * dims_.scale;
  const int n = std::max(1, static_cast<int>(std::lround(distance_m / nominal_step)));
  const double step = distance_m / n, period = step / speed_mps;
  const FloorPose start = current_;
  const auto route = [&](double s) -> FloorPose {
    const double k = curvature_per_m, h0 = start.heading;
    if (std::fabs(k) < 1e-9) return {start.p + s * start.forward(), h0};
    const double h = h0 + k * s;
    return {start.p + Eigen::Vector2d(std::sin(h) - std::sin(h0), std::cos(h0) - std::cos(h)) / k, h};
  };
  const double lift = 0.08 * dims_.scale;
  const int lead = 1, other = 0;
  const auto side_of = [&](int footprint_index) { return footprint_index % 2 == 1 ? lead : other; };
  // Interval 0 starts (pelvis 0 -> step/2, accelerating), intervals 1..n-1 are steady (pelvis
  // (k - 1/2) step -> (k + 1/2) step), interval n closes (pelvis -> n step, decelerating).
  // Interval k < n swings a foot onto footprint k + 1 at route distance (k + 1) step; the closing
  // interval brings the rear foot beside the last footprint.
  for (int k = 0; k <= n; ++k) {
    const double t_begin = t_end_;
    const int side = k == 0 ? lead : (k == n ? side_of(n - 1) : side_of(k + 1));
    const double target_s = k == n ? n * step : (k + 1) * step;
    addSwing(side, t_begin, t_begin + period, footprint(route(target_s), side), lift);
    const int samples = std::max(2, static_cast<int>(std::ceil(period / kSampleStep)));
    for (int i = 1; i <= samples; ++i) {
      const double u = static_cast<double>(i) / samples;
      double s;
      if (k == 0) s = 0.5 * step * u * u;
      else if (k == n) s = (n - 0.5) * step + 0.5 * step * (2 * u - u * u);
      else s = (k - 0.5 + u) * step;
      addPelvis(t_begin + u * period, route(s));
    }
    t_end_ = t_begin + period;
  }
  current_ = route(n * step);
  actions_.push_back("walk " + std::to_string(distance_m) + " m at " + std::to_string(speed_mps) +
                     " m/s, curvature " + std::to_string(curvature_per_m) + " /m");
}

void Body::stand(double duration_s) {
  t_end_ += duration_s;
  addPelvis(t_end_, current_);
  actions_.push_back("stand " + std::to_string(duration_s) + " s");
}

void Body::turn(double angle_rad) {
  const int parts = std::max(1, static_cast<int>(std::ceil(std::fabs(angle_rad) / (0.5 * M_PI) - 1e-9)));
  const double delta = angle_rad / parts;
  const int first = delta > 0 ? 0 : 1;  // the foot on the turning side leads
  for (int p = 0; p < parts; ++p) {
    const FloorPose from = current_;
    FloorPose to = from;
    to.heading += delta;
    for (int j = 0; j < 2; ++j) {
      const int side = j == 0 ? first : 1 - first;
      addSwing(side, t_end_ + j * kSwingSeconds, t_end_ + (j + 1) * kSwingSeconds, footprint(to, side),
               0.05 * dims_.scale);
    }
    const int samples = static_cast<int>(std::ceil(2 * kSwingSeconds / kSampleStep));
    for (int i = 1; i <= samples; ++i) {
      const double u = static_cast<double>(i) / samples;
      addPelvis(t_end_ + 2 * kSwingSeconds * u, lerp(from, to, smoothstep(u)));
    }
    t_end_ += 2 * kSwingSeconds;
    current_ = to;
  }
  actions_.push_back("turn " + std::to_string(angle_rad * 180 / M_PI) + " deg");
}

void Body::sit(double seat_height_m, double back_m, double down_s, double hold_s, double up_s) {
  const FloorPose stand_pose = current_;
  FloorPose seated = stand_pose;
  seated.p -= back_m * stand_pose.forward();
  const auto transition = [&](double duration, bool down) {
    const int samples = std::max(2, static_cast<int>(std::ceil(duration / kSampleStep)));
    for (int i = 1; i <= samples; ++i) {
      const double u = static_cast<double>(i) / samples, w = smoothstep(down ? u : 1 - u);
      addPelvis(t_end_ + duration * u, lerp(stand_pose, seated, w), w, seat_height_m);
    }
    t_end_ += duration;
  };
  transition(down_s, true);
  t_end_ += hold_s;
  addPelvis(t_end_, seated, 1.0, seat_height_m);
  transition(up_s, false);
  actions_.push_back("sit on " + std::to_string(seat_height_m) + " m for " + std::to_string(hold_s) + " s");
}

FloorPose Body::footAt(int side, double t, double& lift) const {
  lift = 0;
  const auto& swings = swings_[side];
  const auto it = std::upper_bound(swings.begin(), swings.end(), t,
                                   [](double time, const Swing& s) { return time < s.t0; });
  if (it == swings.begin()) return foot_start_[side];
  const Swing& s = *std::prev(it);
  if (t >= s.t1) return s.to;
  const double u = (t - s.t0) / (s.t1 - s.t0);
  lift = s.lift * std::sin(M_PI * u);
  return lerp(s.from, s.to, smoothstep(u));
}

bool Body::footPlanted(int side, double t) const {
  for (const Swing& s : swings_[side])
    if (t > s.t0 && t < s.t1) return false;
  return true;
}

Body::State Body::stateAt(double t) const {
  State st;
  const auto it = std::upper_bound(pelvis_.begin(), pelvis_.end(), t,
                                   [](double time, const PelvisSample& s) { return time < s.t; });
  if (it == pelvis_.begin() || it == pelvis_.end()) {
    const PelvisSample& s = it == pelvis_.begin() ? pelvis_.front() : pelvis_.back();
    st.pelvis = s.pose;
    st.sit = s.sit;
    st.seat_height = s.seat_height;
  } else {
    const PelvisSample& a = *std::prev(it);
    const PelvisSample& b = *it;
    const double w = (t - a.t) / (b.t - a.t);
    st.pelvis = lerp(a.pose, b.pose, w);
    st.sit = a.sit + w * (b.sit - a.sit);
    st.seat_height = std::max(a.seat_height, b.seat_height);
  }
  for (int side = 0; side < 2; ++side) st.foot[side] = footAt(side, t, st.lift[side]);
  return st;
}

std::array<SE3, kBodyParts> Body::partPoses(double t) const {
  const State st = stateAt(t);
  const BodyDimensions& d = dims_;
  const Eigen::Matrix3d R_pelvis = rotZ(st.pelvis.heading);
  const Eigen::Vector3d fwd = R_pelvis.col(0);
  // Pelvis height: standing with slightly bent knees, seated just above the seat, and never so high
  // that a leg could not reach its foot.
  const double reach = 0.985 * (d.thigh() + d.shin());
  const double z_stand = d.hip_drop() + d.ankle() + 0.97 * (d.thigh() + d.shin());
  const double z_seated = st.seat_height + 0.065 * d.scale + d.hip_drop();
  double z = z_stand + st.sit * (z_seated - z_stand);
  std::array<Eigen::Vector3d, 2> ankle;
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1.0 : -1.0;
    ankle[side] = Eigen::Vector3d(st.foot[side].p.x(), st.foot[side].p.y(), st.lift[side] + d.ankle());
    const Eigen::Vector2d hip_xy = st.pelvis.p + sign * d.hip_half() * st.pelvis.left();
    const double dxy = (hip_xy - st.foot[side].p).norm();
    z = std::min(z, ankle[side].z() + std::sqrt(std::max(0.0, reach * reach - dxy * dxy)) + d.hip_drop());
  }
  const Eigen::Vector3d origin(st.pelvis.p.x(), st.pelvis.p.y(), z);
  const double lean = 0.5 * std::sin(M_PI * st.sit);
  const Eigen::Matrix3d R_torso = R_pelvis * rotY(lean);

  std::array<SE3, kBodyParts> pose;
  pose[static_cast<int>(BodyPart::Pelvis)] = makePose(R_pelvis, origin);
  pose[static_cast<int>(BodyPart::Torso)] = makePose(R_torso, origin);
  for (int side = 0; side < 2; ++side) {
    const double sign = side == 0 ? 1.0 : -1.0;
    // Arm swing (rad, > 0 forward) against this side's foot lead over the pelvis.
    const double lead = (st.foot[side].p - st.pelvis.p).dot(st.pelvis.forward());
    double swing = std::clamp(-1.1 * lead / d.scale, -0.6, 0.6);
    double elbow = 0.2 + 0.6 * std::max(0.0, swing);
    swing += st.sit * (0.35 - swing);
    elbow += st.sit * (1.0 - elbow);
    const Eigen::Vector3d shoulder =
        origin + R_torso * Eigen::Vector3d(0, sign * d.shoulder_half(), d.shoulder_height());
    const Eigen::Matrix3d R_upper = R_torso * rotY(-swing);
    const Eigen::Vector3d elbow_point = shoulder - d.upper_arm() * R_upper.col(2);
    const int arm = side == 0 ? static_cast<int>(BodyPart::UpperArmLeft) : static_cast<int>(BodyPart::UpperArmRight);
    pose[arm] = makePose(R_upper, shoulder);
    pose[arm + 1] = makePose(R_torso * rotY(-(swing + elbow)), elbow_point);

    const Eigen::Vector3d hip = origin + R_pelvis * Eigen::Vector3d(0, sign * d.hip_half(), -d.hip_drop());
    const Eigen::Vector3d knee = kneePosition(hip, ankle[side], d.thigh(), d.shin(), fwd);
    const int leg = side == 0 ? static_cast<int>(BodyPart::ThighLeft) : static_cast<int>(BodyPart::ThighRight);
    pose[leg] = limbFrame(hip, knee, fwd);
    pose[leg + 1] = limbFrame(knee, ankle[side], fwd);
    pose[leg + 2] = makePose(rotZ(st.foot[side].heading),
                             Eigen::Vector3d(st.foot[side].p.x(), st.foot[side].p.y(), st.lift[side]));
  }
  for (SE3& T : pose) T = T_world_floor_ * T;
  return pose;
}

SE3 Body::partPose(BodyPart part, double t) const { return partPoses(t)[static_cast<int>(part)]; }

std::vector<Body::Box> Body::partBoxes(BodyPart part) const {
  const double s = dims_.scale;
  const auto box = [s](double x0, double x1, double y0, double y1, double z0, double z1, Material m) {
    return Box{s * Eigen::Vector3d(x0, y0, z0), s * Eigen::Vector3d(x1, y1, z1), m};
  };
  // Limb lengths come from dims_ (the boxes end exactly at the next joint).
  const double ua = dims_.upper_arm() / s, fa = dims_.forearm() / s;
  const double th = dims_.thigh() / s, sh = dims_.shin() / s, an = dims_.ankle() / s;
  switch (part) {
    case BodyPart::Pelvis: return {box(-0.11, 0.11, -0.17, 0.17, -0.12, 0.06, Material::Trousers)};
    case BodyPart::Torso:
      return {box(-0.12, 0.12, -0.18, 0.18, 0.06, 0.6, Material::Shirt),
              box(-0.05, 0.05, -0.05, 0.05, 0.6, 0.65, Material::Skin),
              box(-0.1, 0.1, -0.085, 0.085, 0.65, 0.87, Material::Skin),
              box(-0.11, 0.05, -0.095, 0.095, 0.82, 0.9, Material::Hair)};
    case BodyPart::UpperArmLeft:
    case BodyPart::UpperArmRight: return {box(-0.045, 0.045, -0.045, 0.045, -ua, 0.04, Material::Shirt)};
    case BodyPart::ForearmLeft:
    case BodyPart::ForearmRight:
      return {box(-0.04, 0.04, -0.04, 0.04, -0.1, 0, Material::Shirt),
              box(-0.035, 0.035, -0.035, 0.035, -(fa - 0.08), -0.1, Material::Skin),
              box(-0.04, 0.04, -0.02, 0.02, -fa, -(fa - 0.08), Material::Skin)};
    case BodyPart::ThighLeft:
    case BodyPart::ThighRight: return {box(-0.07, 0.07, -0.065, 0.065, -th, 0.03, Material::Trousers)};
    case BodyPart::ShinLeft:
    case BodyPart::ShinRight: return {box(-0.055, 0.055, -0.05, 0.05, -sh, 0, Material::Trousers)};
    case BodyPart::FootLeft:
    case BodyPart::FootRight: return {box(-0.06, 0.2, -0.05, 0.05, 0, an, Material::Shoes)};
    case BodyPart::Count: break;
  }
  return {};
}

nlohmann::json Body::describe() const {
  return {{"scale", dims_.scale}, {"start_time_s", t0_}, {"end_time_s", t_end_}, {"actions", actions_}};
}

}  // namespace ff::synth

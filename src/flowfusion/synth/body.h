#pragma once
// Internal: an articulated person for the synthetic scenes. Twelve rigid parts (pelvis, torso with
// neck and head, upper arms, forearms with hands, thighs, shins, feet), each an axis-aligned box set in
// its own frame, driven by a script of actions: walking along straight or curved routes, stopping
// (a closing step brings the feet together), turning on the spot, standing, sitting down on a seat
// and getting up. Walking is planned as footsteps: a foot in stance keeps one world pose until it
// lifts, the legs reach it by two-link inverse kinematics (the knee bends forward) and the pelvis
// lowers where a straight leg could not reach, so the stance foot is exactly still. Arms swing
// against the legs (an arm's swing follows the opposite foot's lead over the pelvis).
//
// Floor frame: metres, z up, floor at z = 0; T_world_floor places it in the scene's world.
#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/se3.h"

namespace ff::synth {

// A pose on the floor: position (m) and heading (rad about z, 0 = +x); heading is kept unwrapped.
struct FloorPose {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  double heading = 0;
  Eigen::Vector2d forward() const;
  Eigen::Vector2d left() const;
};

enum class BodyPart {
  Pelvis, Torso, UpperArmLeft, ForearmLeft, UpperArmRight, ForearmRight,
  ThighLeft, ShinLeft, FootLeft, ThighRight, ShinRight, FootRight, Count
};
const char* bodyPartName(BodyPart part);
inline constexpr int kBodyParts = static_cast<int>(BodyPart::Count);

// Body dimensions, m (an adult of about 1.75 m at scale 1).
struct BodyDimensions {
  double scale = 1.0;
  double thigh() const { return 0.44 * scale; }
  double shin() const { return 0.42 * scale; }
  double ankle() const { return 0.07 * scale; }       // height of the ankle above the sole
  double hip_half() const { return 0.09 * scale; }    // lateral offset of each hip joint
  double hip_drop() const { return 0.05 * scale; }    // hip joints below the pelvis origin
  double shoulder_half() const { return 0.225 * scale; }
  double shoulder_height() const { return 0.55 * scale; }  // above the pelvis origin, along the torso
  double upper_arm() const { return 0.3 * scale; }
  double forearm() const { return 0.27 * scale; }     // elbow to finger tips
  double foot_width() const { return 0.2 * scale; }   // distance between the feet standing
};

class Body {
 public:
  // Starts standing with the feet together at `start` from time t0 (s).
  Body(const BodyDimensions& dims, const FloorPose& start, double t0, const SE3& T_world_floor = SE3::Identity());

  // Script, each action starting where and when the previous one ended (feet together in between).
  // Walks distance_m along a route of constant curvature (1/m, > 0 turns left) at speed_mps
  // (steady steps; the first and the closing step are half-length steps of the same duration).
  void walk(double distance_m, double speed_mps, double curvature_per_m = 0);
  void stand(double duration_s);
  void turn(double angle_rad);  // on the spot, two foot steps per up to 90 degrees
  // Sits down with the pelvis moving back by back_m onto a seat whose top is seat_height_m, holds,
  // and gets up again to the same standing pose.
  void sit(double seat_height_m, double back_m, double down_s, double hold_s, double up_s);

  double endTime() const { return t_end_; }
  const FloorPose& pose() const { return current_; }  // where the script ends

  // World pose of a part at time t (before t0 and after the end the body holds still).
  SE3 partPose(BodyPart part, double t) const;
  std::array<SE3, kBodyParts> partPoses(double t) const;
  // The part's boxes in its own frame, each with the material it is dressed in.
  enum class Material { Trousers, Shirt, Skin, Hair, Shoes };
  struct Box {
    Eigen::Vector3d lo, hi;  // m
    Material material;
  };
  std::vector<Box> partBoxes(BodyPart part) const;
  // Whether a foot (0 = left, 1 = right) is planted (in stance, not swinging) at time t.
  bool footPlanted(int side, double t) const;
  const BodyDimensions& dimensions() const { return dims_; }
  nlohmann::json describe() const;

 private:
  struct PelvisSample {
    double t;
    FloorPose pose;
    double sit;  // 0 = standing, 1 = seated
    double seat_height;
  };
  struct Swing {
    double t0, t1;
    FloorPose from, to;
    double lift;  // m, peak height of the sole
  };
  struct State {
    FloorPose pelvis;
    double sit = 0, seat_height = 0;
    std::array<FloorPose, 2> foot;
    std::array<double, 2> lift{0, 0};
  };
  State stateAt(double t) const;
  FloorPose footAt(int side, double t, double& lift) const;
  void addSwing(int side, double t0, double t1, const FloorPose& to, double lift);
  void addPelvis(double t, const FloorPose& pose, double sit = 0, double seat_height = 0);
  FloorPose footprint(const FloorPose& pelvis, int side) const;

  BodyDimensions dims_;
  SE3 T_world_floor_;
  double t0_, t_end_;
  FloorPose current_;
  std::array<FloorPose, 2> foot_start_, foot_now_;
  std::array<std::vector<Swing>, 2> swings_;
  std::vector<PelvisSample> pelvis_;  // dense samples, linear in between
  std::vector<std::string> actions_;
};

}  // namespace ff::synth

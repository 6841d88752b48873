#pragma once
// Internal: articulated people (body.h) as moving objects of a SceneModel, the scripts that make them
// walk across a camera's view or sit down on a seat, and the other scripted movers of the hard
// dynamic scenes: objects that rest and then are pushed, large objects close to the camera.
#include <memory>

#include "flowfusion/synth/body.h"
#include "flowfusion/synth/scene_model.h"

namespace ff::synth {

// One moving object per body part (consecutive object indices), dressed in new clothing, skin, hair
// and shoe textures of m.
std::vector<MovingObject> personObjects(SceneModel& m, Rng& rng, const std::shared_ptr<const Body>& body, int person);

// The line a person walks along: across the view of a camera at `eye` looking along `view` (floor
// frame, unit), at distance_m in front, from lateral offset -half_m to +half_m (or back).
struct WalkLine {
  Eigen::Vector2d eye = Eigen::Vector2d::Zero(), view = Eigen::Vector2d::UnitX();
  double distance_m = 2.0, half_m = 1.3;
  Eigen::Vector2d point(double lateral_m) const;
  Eigen::Vector2d lateral() const;  // unit, left of the view
};

// Walks back and forth along the line from t0 until t_end (s): legs of random speed (0.5-1.5 m/s)
// and slight curvature (alternating, so each leg retraces the previous one), sometimes a pause,
// a half turn on the spot at each end.
std::shared_ptr<Body> walkerScript(Rng& rng, const WalkLine& line, double t0, double t_end,
                                   const SE3& T_world_floor = SE3::Identity());
// Walks to the spot in front of the seat (seat_centre: floor position, seat_height_m), turns to face
// the camera, sits down, gets up, walks away, comes back and sits again until t_end.
std::shared_ptr<Body> sitterScript(Rng& rng, const WalkLine& line, const Eigen::Vector2d& seat_centre,
                                   double seat_height_m, double t0, double t_end);

// A chair of seat, backrest and four legs (about 0.45 x 0.45 x 0.9 m), origin on the floor under the
// seat's centre.
Item chairShape(SceneModel& m, Rng& rng);

// Still for rest_s, then pushed along `push` (floor vector, m) over push_s, still for rest_s, pushed
// back, and so on; turns by spin_rad while pushed.
class PushedPath : public ObjectPath {
 public:
  SE3 base = SE3::Identity();
  Eigen::Vector3d push = Eigen::Vector3d::Zero();
  double rest_s = 3.0, push_s = 1.5, spin_rad = 0;
  SE3 T_world_object(double t) const override;
  nlohmann::json describe() const override;
};

// A body part's pose from its body.
class BodyPartPath : public ObjectPath {
 public:
  BodyPartPath(std::shared_ptr<const Body> body, BodyPart part, int person)
      : body_(std::move(body)), part_(part), person_(person) {}
  SE3 T_world_object(double t) const override { return body_->partPose(part_, t); }
  nlohmann::json describe() const override;

 private:
  std::shared_ptr<const Body> body_;
  BodyPart part_;
  int person_;
};

}  // namespace ff::synth

// The hard cases of the synthetic scenes: articulated people (gait, turning, sitting), their masks,
// fast camera rotation, motion blur, objects that rest then move, large movers near the camera.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/synth/body.h"
#include "flowfusion/synth/synthetic_scene.h"

using ff::SE3;
using ff::synth::Body;
using ff::synth::BodyDimensions;
using ff::synth::BodyPart;
using ff::synth::FloorPose;
using ff::synth::SynthConfig;
using ff::synth::SyntheticScene;

namespace {

SynthConfig small(int frames, int people) {
  SynthConfig c;
  c.seed = 4;
  c.width = 160;
  c.height = 120;
  c.frames = frames;
  c.objects = 0;
  c.people = people;
  c.noise = false;
  return c;
}

Eigen::Vector3d partPoint(const Body& body, BodyPart part, double t, const Eigen::Vector3d& p_part) {
  return body.partPose(part, t) * p_part;
}

// Every stretch of time in which a foot stays planted: its pose does not change and its sole is on
// the floor; between stretches it moves.
void expectPlantedFeetStill(const Body& body, double t_begin, double t_end) {
  for (int side = 0; side < 2; ++side) {
    const BodyPart foot = side == 0 ? BodyPart::FootLeft : BodyPart::FootRight;
    bool in_stance = false;
    SE3 stance;
    int stances = 0;
    for (double t = t_begin; t <= t_end; t += 0.004) {
      if (!body.footPlanted(side, t)) {
        in_stance = false;
        continue;
      }
      const SE3 T = body.partPose(foot, t);
      if (!in_stance) {
        if (stances > 0) {
          EXPECT_GT((T.translation() - stance.translation()).norm(), 0.1) << "the foot stepped";
        }
        stance = T;
        in_stance = true;
        ++stances;
      }
      EXPECT_LT((T.translation() - stance.translation()).norm(), 1e-12) << "side " << side << " t " << t;
      EXPECT_TRUE(T.linear().isApprox(stance.linear(), 1e-12)) << "side " << side << " t " << t;
      EXPECT_NEAR(T.translation().z(), 0.0, 1e-12) << "sole on the floor";
    }
    EXPECT_GE(stances, 2) << "side " << side;
  }
}

// The shin ends at the ankle on top of the foot: the inverse kinematics reached the foot.
void expectLegsConnected(const Body& body, double t) {
  const BodyDimensions& d = body.dimensions();
  for (const auto& [shin, foot] : {std::pair{BodyPart::ShinLeft, BodyPart::FootLeft},
                                   std::pair{BodyPart::ShinRight, BodyPart::FootRight}}) {
    const Eigen::Vector3d ankle_shin = partPoint(body, shin, t, Eigen::Vector3d(0, 0, -d.shin()));
    const Eigen::Vector3d ankle_foot = partPoint(body, foot, t, Eigen::Vector3d(0, 0, d.ankle()));
    EXPECT_LT((ankle_shin - ankle_foot).norm(), 1e-6) << "t " << t;
  }
}

}  // namespace

TEST(Body, WalkingStanceFootStillHandsSwingAgainstLegs) {
  const double speed = 1.2;
  Body body(BodyDimensions{}, FloorPose{Eigen::Vector2d(1, 2), 0.3}, 0.0);
  body.walk(4.0, speed);
  expectPlantedFeetStill(body, 0.0, body.endTime());
  for (double t = 0; t < body.endTime(); t += 0.05) expectLegsConnected(body, t);

  // Steady part (after the first and before the closing step): the pelvis keeps the speed, the
  // hands swing against the legs (the left hand is forward while the left foot is behind).
  const double t0 = 1.0, t1 = body.endTime() - 1.0;
  const double dist = (body.partPose(BodyPart::Pelvis, t1).translation() -
                       body.partPose(BodyPart::Pelvis, t0).translation()).head<2>().norm();
  EXPECT_NEAR(dist / (t1 - t0), speed, 0.1 * speed);
  const double fa = body.dimensions().forearm();
  double hand_min = 1e9, hand_max = -1e9, correlation = 0;
  for (double t = t0; t < t1; t += 0.01) {
    const SE3 T_pelvis_world = body.partPose(BodyPart::Pelvis, t).inverse();
    const double hand = (T_pelvis_world * partPoint(body, BodyPart::ForearmLeft, t, Eigen::Vector3d(0, 0, -fa))).x();
    const double foot = (T_pelvis_world * body.partPose(BodyPart::FootLeft, t).translation()).x();
    hand_min = std::min(hand_min, hand);
    hand_max = std::max(hand_max, hand);
    correlation += hand * foot;
  }
  EXPECT_GT(hand_max - hand_min, 0.2) << "the hand swings, m";
  EXPECT_LT(correlation, 0) << "the left arm swings forward while the left leg is behind";
}

TEST(Body, TurnsStopsSitsDownAndGetsUp) {
  Body body(BodyDimensions{}, FloorPose{Eigen::Vector2d(0, 0), 0.0}, 0.0);
  body.walk(1.5, 0.8, 0.3);  // a curve
  const double walked = body.endTime();
  body.stand(1.0);
  body.turn(M_PI);
  const double turned = body.endTime();
  body.sit(0.45, 0.3, 1.0, 2.0, 1.0);
  const double risen = body.endTime();
  body.walk(1.0, 0.6);
  expectPlantedFeetStill(body, 0.0, body.endTime());
  for (double t = 0; t < body.endTime(); t += 0.05) expectLegsConnected(body, t);

  EXPECT_NEAR(body.partPose(BodyPart::Pelvis, walked).linear().col(0).head<2>().dot(
                  Eigen::Vector2d(std::cos(0.45), std::sin(0.45))),
              1.0, 1e-9)
      << "heading after 1.5 m at curvature 0.3 / m";
  // Standing still: every part holds.
  for (int k = 0; k < ff::synth::kBodyParts; ++k) {
    const auto part = static_cast<BodyPart>(k);
    EXPECT_TRUE(body.partPose(part, walked + 0.1).isApprox(body.partPose(part, walked + 0.9), 1e-12)) << k;
  }
  const Eigen::Vector3d before = body.partPose(BodyPart::Pelvis, walked + 0.5).linear().col(0);
  const Eigen::Vector3d after = body.partPose(BodyPart::Pelvis, turned).linear().col(0);
  EXPECT_NEAR(before.dot(after), -1.0, 1e-9) << "half turn";
  // Seated: the pelvis rests just above the seat, the feet stay planted through it all.
  const double seated = turned + 2.0;
  const SE3 pelvis = body.partPose(BodyPart::Pelvis, seated);
  EXPECT_NEAR(pelvis.translation().z() - 0.12, 0.45, 0.03) << "underside of the hips on the seat";
  EXPECT_NEAR((pelvis.translation() - body.partPose(BodyPart::Pelvis, turned).translation()).head<2>().norm(), 0.3,
              1e-9);
  EXPECT_TRUE(body.footPlanted(0, seated) && body.footPlanted(1, seated));
  EXPECT_NEAR(body.partPose(BodyPart::Pelvis, risen).translation().z(),
              body.partPose(BodyPart::Pelvis, turned).translation().z(), 1e-9)
      << "standing again";
}

TEST(People, MaskIsTheVisibleBodyPixels) {
  const SyntheticScene scene(small(90, 2)), twin(small(90, 0));
  ASSERT_EQ(scene.personCount(), 2);
  ASSERT_EQ(scene.objectCount(), 2 * ff::synth::kBodyParts);
  int visible = 0;
  for (int i : {0, 30, 60, 89}) {
    const auto f = scene.render(i), g = twin.render(i);
    ASSERT_EQ(cv::countNonZero(g.mask), 0);
    for (int v = 0; v < f.mask.rows; ++v)
      for (int u = 0; u < f.mask.cols; ++u) {
        const float z = f.depth_clean.at<float>(v, u), z_twin = g.depth_clean.at<float>(v, u);
        if (f.mask.at<uint8_t>(v, u)) {
          ++visible;
          EXPECT_GT(f.object_id.at<uint8_t>(v, u), 0);
          EXPECT_LT(z, z_twin) << "a body pixel lies in front of the room, frame " << i;
        } else {
          EXPECT_EQ(f.object_id.at<uint8_t>(v, u), 0);
          EXPECT_EQ(z, z_twin) << "a pixel without the mask shows the room, frame " << i << " at " << u << "," << v;
        }
      }
  }
  EXPECT_GT(visible, 500) << "people are in view";
}

TEST(People, SameSeedSameImagesAndSittingPerson) {
  SynthConfig c = small(40, 2);
  c.seats = 1;
  c.noise = true;
  c.camera_motion = ff::synth::CameraMotion::Rpy;
  c.camera_angular_speed = 40;
  c.exposure_ms = 10;
  c.exposure_samples = 3;
  const SyntheticScene a(c), b(c);
  for (int i : {0, 39}) {
    const auto fa = a.render(i), fb = b.render(i);
    EXPECT_EQ(cv::norm(fa.frame.color, fb.frame.color, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(fa.frame.depth, fb.frame.depth, cv::NORM_INF), 0);
    EXPECT_EQ(cv::norm(fa.mask, fb.mask, cv::NORM_INF), 0);
  }
  SynthConfig other = c;
  other.seed = 5;
  EXPECT_GT(cv::norm(a.render(10).frame.color, SyntheticScene(other).render(10).frame.color, cv::NORM_L1), 0);
  // Person 0 sits on the seat at some time of a long enough sequence.
  SynthConfig longer = small(600, 1);
  longer.seats = 1;
  const SyntheticScene s(longer);
  double lowest = 1e9;
  for (double t = 0; t < 20; t += 0.1)
    lowest = std::min(lowest, s.person(0)->partPose(BodyPart::Pelvis, t).translation().z());
  EXPECT_LT(lowest, 0.65) << "seated pelvis height, m";
}

TEST(CameraMotion, RpyReachesTheRequestedAngularSpeedAboutAllAxes) {
  SynthConfig c = small(900, 0);
  c.camera_motion = ff::synth::CameraMotion::Rpy;
  c.camera_angular_speed = 45;
  const SyntheticScene s(c);
  double w2 = 0, peak = 0;
  Eigen::Vector3d axis2 = Eigen::Vector3d::Zero();
  for (int i = 0; i + 1 < s.frameCount(); ++i) {
    const SE3 d = s.cameraPose(i).inverse() * s.cameraPose(i + 1);
    const Eigen::AngleAxisd aa(d.linear());
    const Eigen::Vector3d w = aa.axis() * aa.angle() * c.fps * 180 / M_PI;  // deg/s in the camera frame
    w2 += w.squaredNorm();
    axis2 += w.cwiseProduct(w);
    peak = std::max(peak, w.norm());
  }
  const int n = s.frameCount() - 1;
  EXPECT_NEAR(std::sqrt(w2 / n), 45, 0.15 * 45) << "RMS angular speed, deg/s";
  EXPECT_GT(peak, 60) << "peak angular speed, deg/s";
  for (int k = 0; k < 3; ++k) EXPECT_GT(std::sqrt(axis2[k] / n), 15) << "RMS about camera axis " << k;
}

TEST(MotionBlur, OffReproducesTheUnblurredImageAndOnSmearsFastMotion) {
  SynthConfig c = small(10, 1);
  c.camera_motion = ff::synth::CameraMotion::Rpy;
  c.camera_angular_speed = 50;
  SynthConfig blurred = c;
  blurred.exposure_ms = 0;
  blurred.exposure_samples = 5;
  const auto plain = SyntheticScene(c).render(5), off = SyntheticScene(blurred).render(5);
  EXPECT_EQ(cv::norm(plain.frame.color, off.frame.color, cv::NORM_INF), 0) << "exposure 0 is no blur";
  // A still camera and scene: every sub-frame is the same image.
  SynthConfig still = small(10, 0);
  still.camera_speed = 0;
  still.camera_angular_speed = 0;
  SynthConfig still_blur = still;
  still_blur.exposure_ms = 30;
  EXPECT_LE(cv::norm(SyntheticScene(still).render(5).frame.color, SyntheticScene(still_blur).render(5).frame.color,
                     cv::NORM_INF),
            1);
  // Fast rotation: blur removes image gradient energy; depth and mask stay those of the timestamp.
  blurred.exposure_ms = 30;
  const auto on = SyntheticScene(blurred).render(5);
  const auto energy = [](const cv::Mat& bgr) {
    cv::Mat gray, gx;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    cv::Sobel(gray, gx, CV_32F, 1, 0);
    return cv::norm(gx, cv::NORM_L2SQR);
  };
  EXPECT_LT(energy(on.frame.color), 0.8 * energy(plain.frame.color));
  EXPECT_EQ(cv::norm(on.depth_clean, plain.depth_clean, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(on.mask, plain.mask, cv::NORM_INF), 0);
}

TEST(Movers, PushedObjectsRestThenMoveAndNearObjectsAreLarge) {
  SynthConfig c = small(60, 0);
  c.pushed_objects = 2;
  c.near_objects = 1;
  c.rest_s = 1.5;
  const SyntheticScene s(c);
  ASSERT_EQ(s.objectCount(), 3);
  for (int k = 1; k < 3; ++k) {
    const double t0 = s.timestamp(0);
    EXPECT_TRUE(s.objectPose(k, t0).isApprox(s.objectPose(k, t0 + 1.4), 1e-12)) << "rests";
    EXPECT_GT((s.objectPose(k, t0 + 2.5).translation() - s.objectPose(k, t0).translation()).norm(), 0.2) << "pushed";
    EXPECT_NEAR(s.objectPose(k, t0 + 2.5).translation().z(), 0.0, 1e-12) << "slides on the floor";
  }
  double covered = 0;
  for (int i = 0; i < 60; i += 10) {
    const auto f = s.render(i);
    covered += cv::countNonZero(f.object_id == 1) / static_cast<double>(f.mask.total());
  }
  EXPECT_GT(covered / 6, 0.12) << "mean fraction of the view covered by the near box";
}

TEST(People, BadOptionsAreInputErrors) {
  for (auto set : std::vector<std::function<void(SynthConfig&)>>{
           [](SynthConfig& c) { c.people = 9; }, [](SynthConfig& c) { c.seats = -1; },
           [](SynthConfig& c) { c.exposure_ms = -1; }, [](SynthConfig& c) { c.exposure_samples = 1; },
           [](SynthConfig& c) { c.rest_s = -2; }, [](SynthConfig& c) { c.near_objects = 5; }}) {
    SynthConfig c = small(2, 0);
    set(c);
    EXPECT_THROW(SyntheticScene{c}, ff::InputError);
  }
}

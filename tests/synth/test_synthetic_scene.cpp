// Ground truth of the synthetic scenes: analytic depth, masks, poses, determinism, static twin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;
using ff::synth::SynthConfig;
using ff::synth::SyntheticScene;

namespace {

SynthConfig small(int w, int h, int frames, bool noise, uint64_t seed = 7) {
  SynthConfig c;
  c.seed = seed;
  c.width = w;
  c.height = h;
  c.frames = frames;
  c.noise = noise;
  return c;
}

Eigen::Vector3d vec3(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// Ray / box entry distance, independent of the generator's caster: t along p = o + t d.
double boxEntry(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& o,
                const Eigen::Vector3d& d) {
  double t0 = -1e30, t1 = 1e30;
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(d[i]) < 1e-15) {
      if (o[i] < lo[i] || o[i] > hi[i]) return -1;
      continue;
    }
    double a = (lo[i] - o[i]) / d[i], b = (hi[i] - o[i]) / d[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  return (t0 <= t1 && t0 > 0) ? t0 : -1;
}

// Nearest hit along the ray of pixel (u, v) from the scene description: the room's far wall,
// every furniture part (world frame) and every object part (object frame at time t).
// Returns the depth and sets object = index of the object hit, or -1.
double referenceDepth(const SyntheticScene& scene, const nlohmann::json& desc, const ff::SE3& T_world_cam, double t,
                      int u, int v, int& object) {
  const auto& K = scene.camera();
  const Eigen::Vector3d d_c((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
  const Eigen::Vector3d o = T_world_cam.translation(), d = T_world_cam.linear() * d_c;
  const Eigen::Vector3d size = vec3(desc["room"]["size_m"]);
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const double plane = d[i] > 0 ? size[i] : 0.0;
    if (std::fabs(d[i]) > 1e-15) best = std::min(best, (plane - o[i]) / d[i]);
  }
  object = -1;
  for (const auto& item : desc["furniture"])
    for (const auto& p : item["parts"]) {
      const double te = boxEntry(vec3(p["min_m"]), vec3(p["max_m"]), o, d);
      if (te > 0 && te < best) best = te;
    }
  for (int k = 0; k < scene.objectCount(); ++k) {
    const ff::SE3 T_obj_world = scene.objectPose(k, t).inverse();
    const Eigen::Vector3d oo = T_obj_world * o, dd = T_obj_world.linear() * d;
    for (const auto& p : desc["objects"][k]["parts"]) {
      const double te = boxEntry(vec3(p["min_m"]), vec3(p["max_m"]), oo, dd);
      if (te > 0 && te < best) {
        best = te;
        object = k;
      }
    }
  }
  return best;
}

std::string readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

float bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double ax = x - x0, ay = y - y0;
  const auto at = [&](int yy, int xx) { return img.at<float>(yy, xx); };
  return static_cast<float>((at(y0, x0) * (1 - ax) + at(y0, x0 + 1) * ax) * (1 - ay) +
                            (at(y0 + 1, x0) * (1 - ax) + at(y0 + 1, x0 + 1) * ax) * ay);
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace

TEST(SyntheticScene, IntrinsicsScaleWithImageSize) {
  const SyntheticScene full(small(640, 480, 1, false));
  EXPECT_NEAR(full.camera().fx, 517.3, 1e-9);
  EXPECT_NEAR(full.camera().cy, 255.3, 1e-9);
  const SyntheticScene quarter(small(160, 120, 1, false));
  EXPECT_NEAR(quarter.camera().fx, 517.3 / 4, 1e-9);
  EXPECT_NEAR(quarter.camera().cx, (318.6 + 0.5) / 4 - 0.5, 1e-9);
  EXPECT_EQ(quarter.camera().width, 160);
  const auto f = quarter.render(0);
  EXPECT_EQ(f.frame.color.size(), cv::Size(160, 120));
  EXPECT_EQ(f.frame.color.type(), CV_8UC3);
  EXPECT_EQ(f.frame.intensity.type(), CV_32FC1);
  EXPECT_EQ(f.frame.depth.type(), CV_32FC1);
  EXPECT_EQ(f.mask.type(), CV_8UC1);
}

// Every pixel's clean depth equals the nearest analytic intersection with the described room,
// furniture and moving objects, and the mask is exactly the set of pixels whose nearest surface is
// a moving object.
TEST(SyntheticScene, DepthAndMaskMatchAnalyticGeometry) {
  const SyntheticScene scene(small(80, 60, 40, false));
  const nlohmann::json desc = scene.description();
  ASSERT_EQ(desc["objects"].size(), 2u);
  int mask_pixels = 0;
  for (int i : {0, 20, 39}) {
    const auto f = scene.render(i);
    for (int v = 0; v < 60; ++v)
      for (int u = 0; u < 80; ++u) {
        int object = -1;
        const double z = referenceDepth(scene, desc, f.T_world_cam, scene.timestamp(i), u, v, object);
        ASSERT_NEAR(f.depth_clean.at<float>(v, u), z, 1e-5 * z) << "frame " << i << " pixel " << u << "," << v;
        ASSERT_EQ(f.frame.depth.at<float>(v, u), f.depth_clean.at<float>(v, u)) << "noise off: exact depth";
        ASSERT_EQ(f.mask.at<uint8_t>(v, u), object >= 0 ? 255 : 0) << "frame " << i << " pixel " << u << "," << v;
        ASSERT_EQ(f.object_id.at<uint8_t>(v, u), object + 1);
        mask_pixels += object >= 0;
      }
  }
  EXPECT_GT(mask_pixels, 100) << "the moving objects should be in view";
}

TEST(SyntheticScene, FloorDepthIsThePlaneDistance) {
  const SyntheticScene scene(small(160, 120, 1, false));
  const auto f = scene.render(0);
  const auto& K = scene.camera();
  const ff::SE3 T = scene.cameraPose(0);
  int floor_pixels = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      const double z = f.depth_clean.at<float>(v, u);
      const Eigen::Vector3d p_w = T * K.backproject(u, v, z);
      if (std::fabs(p_w.z()) > 1e-4) continue;  // not the floor
      const Eigen::Vector3d d = T.linear() * Eigen::Vector3d((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      EXPECT_NEAR(z, -T.translation().z() / d.z(), 1e-5);
      ++floor_pixels;
    }
  EXPECT_GT(floor_pixels, 160 * 120 / 20) << "a tilted-down hand-held camera sees the floor";
}

// Warping frame A into frame B with the true poses and depth aligns static pixels photometrically;
// pixels of moving objects do not align.
TEST(SyntheticScene, GroundTruthPosesAlignStaticPixelsOnly) {
  const SyntheticScene scene(small(320, 240, 60, true));
  const auto& K = scene.camera();
  int a_index = 0;
  int best = -1;
  for (int i = 0; i < 50; i += 5) {
    const int n = cv::countNonZero(scene.render(i).mask);
    if (n > best) best = n, a_index = i;
  }
  ASSERT_GT(best, 2000) << "need a frame with a moving object in view";
  const auto A = scene.render(a_index), B = scene.render(a_index + 4);
  const ff::SE3 T_b_a = B.T_world_cam.inverse() * A.T_world_cam;
  std::vector<double> err_static, err_object;
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const float z = A.depth_clean.at<float>(v, u);
      const Eigen::Vector3d p_b = T_b_a * K.backproject(u, v, z);
      if (p_b.z() < 0.1) continue;
      const Eigen::Vector2d q = K.project(p_b);
      if (q.x() < 1 || q.y() < 1 || q.x() > K.width - 2 || q.y() > K.height - 2) continue;
      const int qu = static_cast<int>(std::lround(q.x())), qv = static_cast<int>(std::lround(q.y()));
      const double dI = std::fabs(A.frame.intensity.at<float>(v, u) - bilinear(B.frame.intensity, q.x(), q.y()));
      if (A.mask.at<uint8_t>(v, u)) {
        err_object.push_back(dI);
      } else if (!B.mask.at<uint8_t>(qv, qu) && std::fabs(B.depth_clean.at<float>(qv, qu) - p_b.z()) < 0.02 * p_b.z()) {
        err_static.push_back(dI);  // visible in B too
      }
    }
  ASSERT_GT(err_static.size(), 10000u);
  ASSERT_GT(err_object.size(), 1000u);
  const double m_static = median(err_static), m_object = median(err_object);
  // Measured (seed 7, frames 10 -> 14): static 0.004, objects 0.03.
  EXPECT_LT(m_static, 0.01);
  EXPECT_GT(m_object, 0.02);
  EXPECT_GT(m_object, 5 * m_static);
}

TEST(SyntheticScene, StaticTwinHasSameRoomAndTrajectory) {
  SynthConfig dyn = small(160, 120, 30, false), stat = dyn;
  stat.objects = 0;
  const SyntheticScene a(dyn), b(stat);
  EXPECT_EQ(b.objectCount(), 0);
  for (int i : {0, 15, 29}) {
    EXPECT_TRUE(a.cameraPose(i).isApprox(b.cameraPose(i), 0.0)) << i;
    const auto fa = a.render(i), fb = b.render(i);
    EXPECT_EQ(cv::countNonZero(fb.mask), 0);
    cv::Mat diff_depth = (fa.depth_clean != fb.depth_clean) & (fa.mask == 0);
    EXPECT_EQ(cv::countNonZero(diff_depth), 0) << "static surfaces must be identical, frame " << i;
    cv::Mat near_object;
    cv::dilate(fa.mask, near_object, cv::Mat(), cv::Point(-1, -1), 3);
    cv::Mat diff_color;
    cv::absdiff(fa.frame.color, fb.frame.color, diff_color);
    cv::cvtColor(diff_color, diff_color, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(cv::countNonZero(diff_color & (near_object == 0)), 0) << "frame " << i;
  }
}

TEST(SyntheticScene, CameraSpeedMatchesConfiguration) {
  SynthConfig c = small(32, 24, 300, false);
  c.camera_speed = 0.3;
  c.camera_angular_speed = 20;
  const SyntheticScene s(c);
  double v2 = 0, w2 = 0;
  for (int i = 0; i + 1 < s.frameCount(); ++i) {
    const ff::SE3 d = s.cameraPose(i).inverse() * s.cameraPose(i + 1);
    v2 += std::pow(ff::translationNorm(d) * c.fps, 2);
    w2 += std::pow(ff::rotationAngleDeg(d) * c.fps, 2);
  }
  // RMS over 10 s of sinusoids with periods up to ~20 s: within a factor 2 of the long-run RMS.
  EXPECT_NEAR(std::sqrt(v2 / 299), 0.3, 0.15);
  EXPECT_NEAR(std::sqrt(w2 / 299), 20, 10);
}

TEST(SyntheticScene, KinectNoiseHolesAndQuantisation) {
  SynthConfig c = small(320, 240, 1, true);
  const SyntheticScene s(c);
  const auto f = s.render(0);
  int valid = 0, total = 0, clean_in_range = 0;
  std::vector<double> normalised;
  for (int v = 0; v < 240; ++v)
    for (int u = 0; u < 320; ++u) {
      const double zc = f.depth_clean.at<float>(v, u), z = f.frame.depth.at<float>(v, u);
      ++total;
      if (zc >= c.min_depth && zc <= c.max_depth) ++clean_in_range;
      if (z == 0) continue;
      ++valid;
      EXPECT_GE(zc, c.min_depth);
      EXPECT_LE(zc, c.max_depth);
      EXPECT_NEAR(z * 5000.0, std::round(z * 5000.0), 1e-3) << "PNG quantisation";
      const double step = zc * zc / 348.0;  // disparity quantisation
      normalised.push_back((z - zc) / std::sqrt(std::pow(ff::synth::depthNoiseSigma(zc), 2) + step * step / 12));
    }
  EXPECT_LT(valid, clean_in_range) << "holes at depth edges, grazing angles and dropouts";
  EXPECT_GT(valid, 0.8 * clean_in_range);
  double mean = 0, sq = 0;
  for (double x : normalised) mean += x, sq += x * x;
  mean /= normalised.size();
  const double rms = std::sqrt(sq / normalised.size());
  EXPECT_NEAR(mean, 0.0, 0.1);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 1.5);
}

TEST(SyntheticScene, RenderAtMatchesRender) {
  const SyntheticScene s(small(96, 72, 5, true));
  const auto a = s.render(3), b = s.renderAt(s.cameraPose(3), s.timestamp(3));
  EXPECT_EQ(cv::norm(a.frame.color, b.frame.color, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(a.frame.depth, b.frame.depth, cv::NORM_INF), 0);
}

TEST(SyntheticScene, SameSeedGivesIdenticalFiles) {
  ff::testing::TempDir tmp;
  const SynthConfig c = small(96, 72, 3, true, 11);
  ff::synth::writeSequence(SyntheticScene(c), (tmp.path() / "a").string());
  ff::synth::writeSequence(SyntheticScene(c), (tmp.path() / "b").string());
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(tmp.path() / "a")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), tmp.path() / "a");
    ASSERT_TRUE(fs::exists(tmp.path() / "b" / rel)) << rel;
    EXPECT_EQ(readBytes(e.path()), readBytes(tmp.path() / "b" / rel)) << rel;
    ++files;
  }
  // rgb, depth, mask per frame; 2 lists, groundtruth, camera, scene.json, the output manifest
  EXPECT_EQ(files, 3 * 3 + 6);
  SynthConfig other = c;
  other.seed = 12;
  ff::synth::writeSequence(SyntheticScene(other), (tmp.path() / "c").string());
  EXPECT_NE(readBytes(tmp.path() / "a" / "groundtruth.txt"), readBytes(tmp.path() / "c" / "groundtruth.txt"));
}

TEST(SyntheticScene, WrittenSequenceReadsBack) {
  ff::testing::TempDir tmp;
  const SyntheticScene s(small(160, 120, 4, true));
  ff::synth::writeSequence(s, tmp.str());
  const auto seq = ff::TumSequence::open(tmp.str());
  ASSERT_EQ(seq.size(), 4u);
  EXPECT_NEAR(seq.camera().fx, s.camera().fx, 1e-6);
  ASSERT_TRUE(seq.groundtruth());
  ASSERT_TRUE(seq.masksDir());
  const auto scene_json = nlohmann::json::parse(readBytes(tmp.path() / "scene.json"));
  EXPECT_EQ(scene_json["seed"], 7);
  EXPECT_EQ(scene_json["generator_version"], ff::synth::kGeneratorVersion);
  for (size_t i = 0; i < 4; ++i) {
    const auto f = s.render(static_cast<int>(i));
    const auto g = seq.load(i);
    EXPECT_NEAR(g.timestamp, f.frame.timestamp, 1e-6);
    EXPECT_EQ(cv::norm(g.color, f.frame.color, cv::NORM_INF), 0);
    EXPECT_LT(cv::norm(g.depth, f.frame.depth, cv::NORM_INF), 1e-6) << "depth is quantised to the PNG's 1/5000 m";
    ff::SE3 T;
    ASSERT_TRUE(ff::interpolatePose(*seq.groundtruth(), f.frame.timestamp, T));
    EXPECT_LT(ff::translationNorm(T.inverse() * f.T_world_cam), 1e-4);
    const cv::Mat mask = cv::imread((fs::path(*seq.masksDir()) / (ff::timestampName(f.frame.timestamp) + ".png")).string(),
                                    cv::IMREAD_UNCHANGED);
    EXPECT_EQ(cv::norm(mask, f.mask, cv::NORM_INF), 0);
  }
}

TEST(SyntheticScene, BadConfigurationAndOutputAreInputErrors) {
  SynthConfig c = small(64, 48, 2, false);
  c.frames = 0;
  EXPECT_THROW(SyntheticScene{c}, ff::InputError);
  c = small(8, 8, 2, false);
  EXPECT_THROW(SyntheticScene{c}, ff::InputError);
  c = small(64, 48, 2, false);
  c.fps = 0;
  EXPECT_THROW(SyntheticScene{c}, ff::InputError);
  ff::testing::TempDir tmp;
  std::ofstream(tmp.path() / "something.txt") << "x";
  const SyntheticScene s(small(64, 48, 2, false));
  EXPECT_THROW(ff::synth::writeSequence(s, tmp.str()), ff::InputError);
  EXPECT_NO_THROW(ff::synth::writeSequence(s, tmp.str(), true));
}

TEST(SynthCli, WritesSequenceAndRefusesNonEmptyOutput) {
  ff::testing::TempDir tmp;
  const std::string out = (tmp.path() / "seq").string();
  auto r = ff::testing::runFlowfusion("synth " + out + " --frames 3 --width 160 --height 120 --seed 3");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* f : {"rgb.txt", "depth.txt", "groundtruth.txt", "camera.txt", "scene.json"})
    EXPECT_TRUE(fs::exists(fs::path(out) / f)) << f;
  EXPECT_EQ(std::distance(fs::directory_iterator(fs::path(out) / "masks"), fs::directory_iterator{}), 3);
  r = ff::testing::runFlowfusion("synth " + out + " --frames 3 --width 160 --height 120");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
  r = ff::testing::runFlowfusion("synth " + out + " --frames 2 --width 160 --height 120 --objects 0 --overwrite");
  EXPECT_EQ(r.status, 0) << r.output;
  r = ff::testing::runFlowfusion("synth " + (tmp.path() / "x").string() + " --frames 0");
  EXPECT_EQ(r.status, 2) << r.output;
}

// Dataset layouts: a few-frame copy of each dataset's folder, made here with its names, files and
// image size, is recognised with the dataset's intrinsics and depth scale and reads frames.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/error.h"
#include "flowfusion/io/dataset_layout.h"
#include "flowfusion/io/tum_sequence.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// Frames of a width x height sequence, images named rgb/<name>.png and depth/<name>.png.
void writeImages(const fs::path& root, const std::vector<std::string>& names, int width, int height) {
  fs::create_directories(root / "rgb");
  fs::create_directories(root / "depth");
  for (const auto& n : names) {
    cv::imwrite((root / "rgb" / (n + ".png")).string(), cv::Mat(height, width, CV_8UC3, cv::Scalar(40, 80, 120)));
    cv::imwrite((root / "depth" / (n + ".png")).string(), cv::Mat(height, width, CV_16U, cv::Scalar(5000)));
  }
}

// A TUM-style folder: rgb.txt, depth.txt and groundtruth.txt over three frames.
void writeTumLists(const fs::path& root, int width, int height) {
  const std::vector<std::string> stamps = {"1548266469.107720", "1548266469.143790", "1548266469.179960"};
  writeImages(root, stamps, width, height);
  std::string rgb = "# color images\n", depth = "# depth maps\n", gt = "# timestamp tx ty tz qx qy qz qw\n";
  for (const auto& t : stamps) {
    rgb += t + " rgb/" + t + ".png\n";
    depth += t + " depth/" + t + ".png\n";
    gt += t + " 0 0 0 0 0 0 1\n";
  }
  writeText(root / "rgb.txt", rgb);
  writeText(root / "depth.txt", depth);
  writeText(root / "groundtruth.txt", gt);
}

void expectCamera(const DatasetCamera& d, Dataset dataset, std::vector<double> values) {
  EXPECT_EQ(d.dataset, dataset) << d.name;
  const CameraIntrinsics& c = d.camera.intrinsics;
  EXPECT_DOUBLE_EQ(c.fx, values[0]) << d.name;
  EXPECT_DOUBLE_EQ(c.fy, values[1]) << d.name;
  EXPECT_DOUBLE_EQ(c.cx, values[2]) << d.name;
  EXPECT_DOUBLE_EQ(c.cy, values[3]) << d.name;
  EXPECT_EQ(c.width, values[4]) << d.name;
  EXPECT_EQ(c.height, values[5]) << d.name;
  EXPECT_EQ(d.depth_scale, 5000) << d.name;
}

TEST(DatasetLayout, BonnIsRecognisedByNameWithItsCalibration) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "rgbd_bonn_balloon";
  writeTumLists(root, 640, 480);
  const auto d = detectDataset(root.string());
  ASSERT_TRUE(d.has_value());
  expectCamera(*d, Dataset::kBonn, {542.822841, 542.576870, 315.593520, 237.756098, 640, 480});
  EXPECT_DOUBLE_EQ(d->camera.distortion.k1, 0.039903);
  EXPECT_DOUBLE_EQ(d->camera.distortion.p2, -0.000144);
  const TumSequence s = TumSequence::open(root.string());
  EXPECT_DOUBLE_EQ(s.camera().fx, 542.822841);
  ASSERT_NE(s.undistorter(), nullptr);
  EXPECT_EQ(s.load(2).depth.at<float>(240, 320), 1.0f);
}

TEST(DatasetLayout, TumIsRecognisedByNameForEachCamera) {
  for (int n : {1, 2, 3}) {
    const auto d = datasetCameraFromName("rgbd_dataset_freiburg" + std::to_string(n) + "_walking_xyz");
    ASSERT_TRUE(d.has_value());
    EXPECT_EQ(d->dataset, Dataset::kTum);
    EXPECT_EQ(d->camera.intrinsics.fx, freiburgPreset(n)->fx);
    EXPECT_EQ(d->depth_scale, 5000);
  }
  EXPECT_FALSE(datasetCameraFromName("my_walk").has_value());
}

TEST(DatasetLayout, IclNuimReadsItsAssociationsAndTrajectory) {
  ff::testing::TempDir tmp;
  for (const std::string name : {"living_room_traj0_frei_png", "renamed"}) {
    const fs::path root = tmp.path() / name;
    writeImages(root, {"0", "1", "2"}, 640, 480);
    writeText(root / "associations.txt", "0 depth/0.png 0 rgb/0.png\n1 depth/1.png 1 rgb/1.png\n2 depth/2.png 2 rgb/2.png\n");
    writeText(root / "livingRoom0.gt.freiburg", "0 0 0 0 0 0 0 1\n1 0.01 0 0 0 0 0 1\n2 0.02 0 0 0 0 0 1\n");
    const auto d = detectDataset(root.string());
    ASSERT_TRUE(d.has_value()) << name;
    expectCamera(*d, Dataset::kIclNuim, {481.20, 480.00, 319.50, 239.50, 640, 480});
    EXPECT_TRUE(d->camera.distortion.none());
    const TumSequence s = TumSequence::open(root.string());
    ASSERT_EQ(s.size(), 3u) << name;
    EXPECT_EQ(s.entry(1).rgb_path, (root / "rgb/1.png").string());
    EXPECT_EQ(s.entry(1).depth_path, (root / "depth/1.png").string());
    ASSERT_TRUE(s.groundtruth().has_value());
    EXPECT_DOUBLE_EQ(s.groundtruth()->at(2).T_world_cam.translation().x(), 0.02);
    EXPECT_EQ(s.load(0).depth.at<float>(0, 0), 1.0f);
  }
}

TEST(DatasetLayout, Eth3dReadsCalibrationTxtAndTheImageSize) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "sofa_1";
  writeTumLists(root, 739, 458);
  writeText(root / "calibration.txt", "726.21081542969 726.21081542969 359.2048034668 202.47247314453\n");
  const auto d = detectDataset(root.string());
  ASSERT_TRUE(d.has_value());
  expectCamera(*d, Dataset::kEth3d, {726.21081542969, 726.21081542969, 359.2048034668, 202.47247314453, 739, 458});
  const TumSequence s = TumSequence::open(root.string());
  EXPECT_EQ(s.load(0).depth.cols, 739);
  writeText(root / "calibration.txt", "726.2 726.2 359.2\n");
  try {
    detectDataset(root.string());
    ADD_FAILURE() << "a short calibration.txt was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("calibration.txt:1"), std::string::npos) << e.what();
  }
}

TEST(DatasetLayout, IclNuimWithTwoTrajectoriesNamesThemRatherThanDroppingGroundTruth) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "living_room_traj0_frei_png";
  writeImages(root, {"0", "1"}, 640, 480);
  writeText(root / "associations.txt", "0 depth/0.png 0 rgb/0.png\n1 depth/1.png 1 rgb/1.png\n");
  writeText(root / "livingRoom0.gt.freiburg", "0 0 0 0 0 0 0 1\n1 0.01 0 0 0 0 0 1\n");
  writeText(root / "livingRoom1.gt.freiburg", "0 0 0 0 0 0 0 1\n1 0.03 0 0 0 0 0 1\n");
  const std::string message = testing::inputErrorOf([&] { TumSequence::open(root.string()); });
  EXPECT_NE(message.find("2 ground-truth trajectories"), std::string::npos) << message;
  EXPECT_NE(message.find("livingRoom0.gt.freiburg"), std::string::npos) << message;
  EXPECT_NE(message.find("livingRoom1.gt.freiburg"), std::string::npos) << message;
  // groundtruth.txt says which one.
  writeText(root / "groundtruth.txt", "0 0 0 0 0 0 0 1\n1 0.03 0 0 0 0 0 1\n");
  const TumSequence s = TumSequence::open(root.string());
  ASSERT_TRUE(s.groundtruth().has_value());
  EXPECT_DOUBLE_EQ(s.groundtruth()->at(1).T_world_cam.translation().x(), 0.03);
}

TEST(DatasetLayout, Eth3dWithAssociationsTakesItsSizeFromTheFirstImage) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "table_3";
  writeImages(root, {"0", "1"}, 640, 480);
  writeText(root / "associations.txt", "0 rgb/0.png 0 depth/0.png\n1 rgb/1.png 1 depth/1.png\n");
  writeText(root / "calibration.txt", "726.2 726.2 319.5 239.5\n");
  const auto d = detectDataset(root.string());
  ASSERT_TRUE(d.has_value());
  expectCamera(*d, Dataset::kEth3d, {726.2, 726.2, 319.5, 239.5, 640, 480});
  const TumSequence s = TumSequence::open(root.string());
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s.load(1).depth.cols, 640);
}

TEST(DatasetLayout, CameraTxtAndCameraOverrideTheDataset) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "rgbd_bonn_crowd";
  writeTumLists(root, 640, 480);
  SequenceOptions o;
  o.camera = "500,500,319.5,239.5";
  EXPECT_EQ(TumSequence::open(root.string(), o).camera().fx, 500);
  writeText(root / "camera.txt", "520 521 320 240 640 480\n");
  EXPECT_EQ(TumSequence::open(root.string()).camera().fx, 520);
}

TEST(DatasetLayout, AnUnknownFolderSaysWhatWasLookedFor) {
  ff::testing::TempDir tmp;
  const fs::path root = tmp.path() / "my_walk";
  writeTumLists(root, 64, 48);
  EXPECT_FALSE(detectDataset(root.string()).has_value());
  try {
    TumSequence::open(root.string());
    ADD_FAILURE() << "no camera was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    for (const std::string part : {"my_walk", "--camera", "camera.txt", "rgbd_dataset_freiburgN_", "rgbd_bonn_",
                                   "calibration.txt", "associations.txt"})
      EXPECT_NE(m.find(part), std::string::npos) << part << " not in: " << m;
  }
  fs::remove(root / "rgb.txt");
  fs::remove(root / "depth.txt");
  writeText(root / "camera.txt", "50 50 31.5 23.5 64 48\n");
  try {
    TumSequence::open(root.string());
    ADD_FAILURE() << "a folder without lists was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("associations.txt"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ff

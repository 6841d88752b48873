// TUM-layout reading: tiny hand-made folders, one defect each, and the error each must produce.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/io/tum_sequence.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

constexpr int kW = 64, kH = 48;

void writeText(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

// 16-bit depth where pixel (x, y) holds raw = 5000 + 10 x + y (1 m + ...).
cv::Mat depthRaw(int w = kW, int h = kH) {
  cv::Mat d(h, w, CV_16U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d.at<uint16_t>(y, x) = static_cast<uint16_t>(5000 + 10 * x + y);
  return d;
}
cv::Mat colour(int w = kW, int h = kH) { return cv::Mat(h, w, CV_8UC3, cv::Scalar(10, 100, 200)); }

// A good sequence: 3 colour frames at 1.00, 1.10, 1.20 s, depth at 1.005, 1.11 and 1.31 (the
// last colour frame has no depth within 0.02 s), camera.txt.
struct Folder {
  explicit Folder(const fs::path& root_in) : root(root_in) {
    fs::create_directories(root / "rgb");
    fs::create_directories(root / "depth");
    for (const char* t : {"1.000000", "1.100000", "1.200000"})
      cv::imwrite((root / "rgb" / (std::string(t) + ".png")).string(), colour());
    for (const char* t : {"1.005000", "1.110000", "1.310000"})
      cv::imwrite((root / "depth" / (std::string(t) + ".png")).string(), depthRaw());
    writeText(root / "rgb.txt",
              "# color images\n1.000000 rgb/1.000000.png\n1.100000 rgb/1.100000.png\n1.200000 rgb/1.200000.png\n");
    writeText(root / "depth.txt",
              "# depth maps\n1.005000 depth/1.005000.png\n1.110000 depth/1.110000.png\n"
              "1.310000 depth/1.310000.png\n");
    writeText(root / "camera.txt", "# fx fy cx cy w h\n50 51 31.5 23.5 64 48\n");
  }
  fs::path root;
  std::string str() const { return root.string(); }
};

// Runs f, expects InputError whose message contains every one of `needles`.
template <typename F>
void expectInputError(F&& f, std::initializer_list<std::string> needles) {
  try {
    f();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& n : needles) EXPECT_NE(msg.find(n), std::string::npos) << "'" << msg << "' lacks '" << n << "'";
  }
}

TEST(TumSequence, GoodFolderOpensAndLoads) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  const TumSequence s = TumSequence::open(f.str());
  EXPECT_EQ(s.camera().width, kW);
  EXPECT_EQ(s.camera().height, kH);
  EXPECT_DOUBLE_EQ(s.camera().fx, 50);
  EXPECT_DOUBLE_EQ(s.camera().fy, 51);
  EXPECT_DOUBLE_EQ(s.camera().cx, 31.5);
  EXPECT_FALSE(s.groundtruth().has_value());
  EXPECT_FALSE(s.masksDir().has_value());
  // Frame 1.2 has no depth within 0.02 s (nearest 1.11 and 1.31) and is dropped.
  ASSERT_EQ(s.size(), 2u);
  EXPECT_DOUBLE_EQ(s.entry(0).rgb_timestamp, 1.0);
  EXPECT_DOUBLE_EQ(s.entry(0).depth_timestamp, 1.005);
  EXPECT_DOUBLE_EQ(s.entry(1).rgb_timestamp, 1.1);
  EXPECT_DOUBLE_EQ(s.entry(1).depth_timestamp, 1.11);

  const RgbdFrame fr = s.load(1);
  EXPECT_DOUBLE_EQ(fr.timestamp, 1.1);
  EXPECT_EQ(fr.color.type(), CV_8UC3);
  EXPECT_EQ(fr.depth.type(), CV_32F);
  EXPECT_EQ(fr.depth.cols, kW);
  EXPECT_EQ(fr.depth.rows, kH);
  // raw 5000 + 10 x + y at 5000 units per metre.
  EXPECT_NEAR(fr.depth.at<float>(0, 0), 1.0f, 1e-6);
  EXPECT_NEAR(fr.depth.at<float>(7, 30), (5000 + 300 + 7) / 5000.0f, 1e-6);
  EXPECT_EQ(fr.intensity.type(), CV_32F);
}

TEST(TumSequence, DepthScaleOption) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  SequenceOptions o;
  o.tum.depth_scale = 1000;
  const RgbdFrame fr = TumSequence::open(f.str(), o).load(0);
  EXPECT_NEAR(fr.depth.at<float>(0, 0), 5.0f, 1e-6);
}

TEST(TumSequence, MissingRgbTxt) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  fs::remove(f.root / "rgb.txt");
  expectInputError([&] { TumSequence::open(f.str()); }, {"rgb.txt"});
}

TEST(TumSequence, MissingFolder) {
  testing::TempDir tmp;
  const std::string dir = (tmp.path() / "nosuch").string();
  expectInputError([&] { TumSequence::open(dir); }, {dir});
}

TEST(TumSequence, MissingOrUnreadableImage) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  fs::remove(f.root / "rgb" / "1.000000.png");
  writeText(f.root / "depth" / "1.110000.png", "this is not a PNG");
  const TumSequence s = TumSequence::open(f.str());
  expectInputError([&] { s.load(0); }, {"1.000000.png"});
  expectInputError([&] { s.load(1); }, {"depth", "1.110000.png"});
}

TEST(TumSequence, WrongImageSize) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  cv::imwrite((f.root / "rgb" / "1.100000.png").string(), colour(32, 24));
  cv::imwrite((f.root / "depth" / "1.005000.png").string(), depthRaw(32, 24));
  const TumSequence s = TumSequence::open(f.str());
  expectInputError([&] { s.load(0); }, {"depth/1.005000.png", "32x24"});
  expectInputError([&] { s.load(1); }, {"rgb/1.100000.png", "32x24"});
}

TEST(TumSequence, EightBitDepthIsRejected) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  cv::imwrite((f.root / "depth" / "1.005000.png").string(), cv::Mat(kH, kW, CV_8U, cv::Scalar(100)));
  const TumSequence s = TumSequence::open(f.str());
  expectInputError([&] { s.load(0); }, {"1.005000.png", "16-bit"});
}

TEST(TumSequence, BadFileLists) {
  struct Case {
    const char* name;
    std::string rgb_txt;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {"unsorted", "1.1 rgb/1.100000.png\n1.0 rgb/1.000000.png\n", "rgb.txt:2"},
      {"duplicate", "1.0 rgb/1.000000.png\n1.0 rgb/1.100000.png\n", "duplicate"},
      {"empty", "# only a comment\n\n", "empty"},
      {"malformed", "1.0 rgb/1.000000.png\nnot-a-number rgb/x.png\n", "rgb.txt:2"},
      {"missing filename", "1.0\n", "rgb.txt:1"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    testing::TempDir tmp;
    Folder f(tmp.path() / "seq");
    writeText(f.root / "rgb.txt", c.rgb_txt);
    expectInputError([&] { TumSequence::open(f.str()); }, {"rgb.txt", c.needle});
  }
}

TEST(TumSequence, NoDepthWithinLimit) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  writeText(f.root / "depth.txt", "5.0 depth/1.005000.png\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {f.str(), "0.02"});
}

TEST(TumSequence, NoIntrinsicsSaysHowToGiveThem) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "my_sequence");
  fs::remove(f.root / "camera.txt");
  expectInputError([&] { TumSequence::open(f.str()); }, {"my_sequence", "--camera", "camera.txt"});
}

TEST(TumSequence, FolderNamePicksFreiburgPreset) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "rgbd_dataset_freiburg2_x");
  fs::remove(f.root / "camera.txt");
  const TumSequence s = TumSequence::open(f.str());
  const CameraIntrinsics fr2 = *freiburgPreset(2);
  EXPECT_DOUBLE_EQ(s.camera().fx, fr2.fx);
  EXPECT_DOUBLE_EQ(s.camera().cy, fr2.cy);
  EXPECT_DOUBLE_EQ(s.distortion().k1, freiburgDistortion(2)->k1);
  EXPECT_NE(s.undistorter(), nullptr);
  // The preset is 640x480, these images are not: loading says so.
  expectInputError([&] { s.load(0); }, {"640x480"});
  SequenceOptions raw;
  raw.undistort = false;
  EXPECT_EQ(TumSequence::open(f.str(), raw).undistorter(), nullptr);
}

TEST(TumSequence, CameraOptionOverrides) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "rgbd_dataset_freiburg2_x");
  SequenceOptions o;
  o.camera = "fr3";
  EXPECT_DOUBLE_EQ(TumSequence::open(f.str(), o).camera().fx, freiburgPreset(3)->fx);
  o.camera = "40,41,32,24,64,48";
  const TumSequence s = TumSequence::open(f.str(), o);
  EXPECT_DOUBLE_EQ(s.camera().fx, 40);
  EXPECT_DOUBLE_EQ(s.camera().fy, 41);
  EXPECT_NO_THROW(s.load(0));
  o.camera = "fr9";
  expectInputError([&] { TumSequence::open(f.str(), o); }, {"--camera", "fr9"});
}

TEST(TumSequence, BadCameraFile) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  writeText(f.root / "camera.txt", "# fx fy cx cy w h\n50 51 31.5\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {"camera.txt:2", "fx fy cx cy width height", "50 51 31.5"});
  writeText(f.root / "camera.txt", "0 51 31.5 23.5 64 48\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {"camera.txt:1", "focal lengths"});
  writeText(f.root / "camera.txt", "50 51 1e300 23.5 64 48\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {"camera.txt:1", "principal point"});
  writeText(f.root / "camera.txt", "# nothing\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {"camera.txt", "no intrinsics"});
  writeText(f.root / "camera.txt", "50 51 31.5 23.5 64 48 0.1 0.2\n");
  expectInputError([&] { TumSequence::open(f.str()); }, {"camera.txt:1", "k1 k2 p1 p2 k3"});
}

TEST(TumSequence, CameraFileWithDistortionUndistortsOnLoading) {
  testing::TempDir tmp;
  Folder f(tmp.path() / "seq");
  writeText(f.root / "camera.txt", "50 51 31.5 23.5 64 48 0.1 -0.05 0 0 0\n");
  const TumSequence s = TumSequence::open(f.str());
  EXPECT_DOUBLE_EQ(s.distortion().k1, 0.1);
  ASSERT_NE(s.undistorter(), nullptr);
  const RgbdFrame frame = s.load(0);
  EXPECT_EQ(frame.width(), kW);
  EXPECT_EQ(frame.height(), kH);
}

TEST(TumSequence, WriterRoundTrip) {
  testing::TempDir tmp;
  const std::string dir = (tmp.path() / "written").string();
  const CameraIntrinsics cam{50, 51, 31.5, 23.5, kW, kH};
  TumWriter w(dir, cam);
  cv::Mat depth_m(kH, kW, CV_32F, cv::Scalar(1.2345f));
  cv::Mat mask = cv::Mat::zeros(kH, kW, CV_8U);
  mask(cv::Rect(0, 0, 10, 10)).setTo(255);
  SE3 T = SE3::Identity();
  T.translation() << 0.1, 0.2, 0.3;
  w.add(2.5, colour(), depth_m, T, mask);
  w.add(2.6, colour(), depth_m, T, mask);
  w.finish("test");
  const TumSequence s = TumSequence::open(dir);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_DOUBLE_EQ(s.camera().fy, 51);
  ASSERT_TRUE(s.groundtruth().has_value());
  ASSERT_EQ(s.groundtruth()->size(), 2u);
  EXPECT_NEAR((s.groundtruth()->at(1).T_world_cam.translation() - T.translation()).norm(), 0, 1e-6);
  EXPECT_TRUE(s.masksDir().has_value());
  EXPECT_NEAR(s.load(1).depth.at<float>(5, 5), 1.2345f, 1.0 / 5000);
  EXPECT_EQ(timestampName(2.5), "2.500000");
}

TEST(PrepareOutputDir, NonEmptyWithoutOverwriteKeepsFiles) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "out";
  writeText(out / "keep.txt", "precious");
  expectInputError([&] { prepareOutputDir(out.string(), false); }, {out.string(), "--overwrite"});
  std::ifstream in(out / "keep.txt");
  std::string content;
  in >> content;
  EXPECT_EQ(content, "precious");
  EXPECT_NO_THROW(prepareOutputDir(out.string(), true));
  EXPECT_TRUE(fs::exists(out / "keep.txt"));
  EXPECT_NO_THROW(prepareOutputDir((tmp.path() / "fresh" / "nested").string(), false));
  EXPECT_TRUE(fs::is_directory(tmp.path() / "fresh" / "nested"));
  writeText(tmp.path() / "file", "x");
  expectInputError([&] { prepareOutputDir((tmp.path() / "file").string(), true); }, {"not a folder"});
}

}  // namespace
}  // namespace ff

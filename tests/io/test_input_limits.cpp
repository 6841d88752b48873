// Hostile input files: huge declared images, huge timestamps, garbage and endless lines, a folder
// where a file belongs. Each is an InputError naming the file, decided before anything large is
// allocated, with the offending text cut short in the message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "flowfusion/core/error.h"
#include "flowfusion/core/image_file.h"
#include "flowfusion/io/trajectory_io.h"
#include "flowfusion/io/tum_sequence.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

// A valid PNG whose IHDR then declares w x h (the CRC no longer matches: only the header is read).
void writePngDeclaring(const fs::path& p, uint32_t w, uint32_t h, int type = CV_8UC3) {
  cv::imwrite(p.string(), cv::Mat(4, 4, type, cv::Scalar::all(7)));
  std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
  const unsigned char size[8] = {static_cast<unsigned char>(w >> 24), static_cast<unsigned char>(w >> 16),
                                 static_cast<unsigned char>(w >> 8),  static_cast<unsigned char>(w),
                                 static_cast<unsigned char>(h >> 24), static_cast<unsigned char>(h >> 16),
                                 static_cast<unsigned char>(h >> 8),  static_cast<unsigned char>(h)};
  f.seekp(16);
  f.write(reinterpret_cast<const char*>(size), 8);
}

TEST(ImageFile, HeaderIsReadBeforeDecoding) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "huge.png";
  writePngDeclaring(p, 100000, 100000);
  ASSERT_EQ(readPngSize(p.string()), cv::Size(100000, 100000));
  const std::string any = testing::inputErrorOf([&] { readImageFile(p.string(), cv::IMREAD_UNCHANGED, "mask image"); });
  EXPECT_NE(any.find(p.string() + ": mask image declares 100000x100000 pixels"), std::string::npos) << any;
  writePngDeclaring(p, 20000, 20000);
  const std::string sized =
      testing::inputErrorOf([&] { readImageFile(p.string(), cv::IMREAD_UNCHANGED, "colour image", cv::Size(64, 48)); });
  EXPECT_NE(sized.find("colour image is 20000x20000, expected 64x48"), std::string::npos) << sized;
  EXPECT_FALSE(readPngSize((tmp.path() / "missing.png").string()));
  EXPECT_TRUE(readImageFile((tmp.path() / "missing.png").string(), cv::IMREAD_UNCHANGED, "image").empty());
}

TEST(InputLimits, HugeTimestampIsRefusedWithTheLine) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "rgb.txt";
  std::ofstream(p) << "1.0 rgb/a.png\n1e300 rgb/b.png\n";
  const std::string msg = testing::inputErrorOf([&] { readFileList(p.string()); });
  EXPECT_NE(msg.find(p.string() + ":2: timestamp 1e+300 s is out of range"), std::string::npos) << msg;
  std::ofstream(p) << "-1e11 rgb/a.png\n";
  EXPECT_NE(testing::inputErrorOf([&] { readFileList(p.string()); }).find("out of range"), std::string::npos);
}

TEST(InputLimits, GarbageAndLongLinesAreCutInMessages) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "groundtruth.txt";
  std::ofstream(p) << "1.0 " << std::string(10 * 1024 * 1024, 'z') << "\n";
  const std::string long_msg = testing::inputErrorOf([&] { readTrajectory(p.string()); });
  EXPECT_LT(long_msg.size(), 400u);
  EXPECT_NE(long_msg.find("... (10485764 characters)"), std::string::npos) << long_msg.substr(0, 400);
  std::ofstream(p, std::ios::binary) << std::string("1.0 \x01\xff\x1b[2J", 10) << "\n";
  const std::string garbage = testing::inputErrorOf([&] { readTrajectory(p.string()); });
  EXPECT_NE(garbage.find("1.0 \\x01\\xff\\x1b[2J"), std::string::npos) << garbage;
}

TEST(InputLimits, FolderWhereAListBelongsIsNamed) {
  testing::TempDir tmp;
  fs::create_directories(tmp.path() / "groundtruth.txt");
  const std::string msg = testing::inputErrorOf([&] { readTrajectory((tmp.path() / "groundtruth.txt").string()); });
  EXPECT_NE(msg.find("groundtruth.txt: is a folder, not a trajectory file"), std::string::npos) << msg;
}

}  // namespace
}  // namespace ff

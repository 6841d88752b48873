// readImageFile(..., IMREAD_UNCHANGED) gives exactly cv::imread's image: through libdeflate
// (core/png_decoder.h) for 8- and 16-bit grey and colour PNGs, through OpenCV for the rest and for
// damaged files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <vector>

#include "flowfusion/core/image_file.h"
#include "testing/test_util.h"

namespace ff {
namespace {

// Smooth ramps with noise, so that the encoder picks every filter type (none, sub, up, average,
// Paeth) on some rows.
cv::Mat textured(int type, uint32_t seed) {
  cv::Mat m(37, 53, type);
  std::mt19937 rng(seed);
  const double top = CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols * m.channels(); ++x) {
      const double v = y < 12 ? top * x / (m.cols * m.channels()) : top * (std::sin(0.3 * x + 0.2 * y) * 0.4 + 0.5);
      const double noise = y % 3 == 0 ? static_cast<double>(rng() % 9) - 4 : 0;
      const double value = std::clamp(v + noise * top / 255, 0.0, top);
      if (CV_MAT_DEPTH(type) == CV_16U)
        m.ptr<uint16_t>(y)[x] = static_cast<uint16_t>(value);
      else
        m.ptr<uint8_t>(y)[x] = static_cast<uint8_t>(value);
    }
  return m;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0;
}

void expectAsOpenCv(const std::string& path) {
  const cv::Mat ours = readImageFile(path, cv::IMREAD_UNCHANGED, "image");
  const cv::Mat opencv = cv::imread(path, cv::IMREAD_UNCHANGED);
  EXPECT_TRUE(sameImage(ours, opencv)) << path;
}

TEST(ImageFileDecoding, GreyAndColourPngsOfBothDepthsAreOpenCvsImages) {
  testing::TempDir tmp;
  uint32_t seed = 1;
  for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3, CV_8UC4})
    for (const int level : {0, 1, 3, 9}) {
      const std::string path = (tmp.path() / (std::to_string(type) + "_" + std::to_string(level) + ".png")).string();
      ASSERT_TRUE(cv::imwrite(path, textured(type, seed++), {cv::IMWRITE_PNG_COMPRESSION, level}));
      expectAsOpenCv(path);
    }
}

TEST(ImageFileDecoding, DamagedPngsAreLeftToOpenCv) {
  testing::TempDir tmp;
  const std::string good = (tmp.path() / "good.png").string();
  ASSERT_TRUE(cv::imwrite(good, textured(CV_16UC1, 7)));
  std::vector<char> bytes;
  {
    std::ifstream in(good, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const auto write = [&](const std::string& name, const std::vector<char>& b) {
    const std::string path = (tmp.path() / name).string();
    std::ofstream(path, std::ios::binary).write(b.data(), static_cast<std::streamsize>(b.size()));
    return path;
  };
  std::vector<char> flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;  // inside the image data: its chunk's CRC fails
  expectAsOpenCv(write("flipped.png", flipped));
  const std::vector<char> truncated(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() * 2 / 3));
  expectAsOpenCv(write("truncated.png", truncated));
  const std::vector<char> header_only(bytes.begin(), bytes.begin() + 33);
  expectAsOpenCv(write("header_only.png", header_only));
}

TEST(ImageFileDecoding, RealTumFramesAreOpenCvsImages) {
  FF_REQUIRE_SHARED_DATA(dir);
  int checked = 0;
  for (const char* folder : {"rgb", "depth"}) {
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(dir) / folder)) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (size_t i = 0; i < files.size() && i < 3; ++i, ++checked) expectAsOpenCv(files[i].string());
  }
  EXPECT_EQ(checked, 6);
}

}  // namespace
}  // namespace ff

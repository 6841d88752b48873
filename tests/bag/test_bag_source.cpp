// ROS 1 bags: bags written here with the rosbag C++ API from a small synthetic sequence, in every
// supported encoding, compressed and not, read back as the TUM folder of the same frames reads;
// the whole run on a bag (and on its `convert`ed folder) gives the folder's trajectory and masks;
// bad bags give InputErrors that say what is wrong.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/core/config.h"
#include "flowfusion/core/error.h"
#include "flowfusion/io/bag_convert.h"
#include "flowfusion/io/bag_source.h"
#include "flowfusion/io/tum_folder_source.h"
#include "flowfusion/pipeline/run.h"
#include "flowfusion/synth/synthetic_scene.h"
#include "testing/run_output.h"
#include "testing/test_util.h"

#ifdef FLOWFUSION_HAVE_ROSBAG
#include <rosbag/bag.h>

#include "flowfusion/io/ros_messages.h"
#endif

namespace fs = std::filesystem;

namespace ff {
namespace {

using testing::inputErrorOf;

#ifndef FLOWFUSION_HAVE_ROSBAG

TEST(BagSource, ABuildWithoutRosbagSaysHowToEnableBags) {
  EXPECT_FALSE(bagSupportBuilt());
  const std::string message = inputErrorOf([] { openFrameSource("walk.bag", SequenceOptions{}); });
  EXPECT_NE(message.find("librosbag-storage-dev"), std::string::npos) << message;
  EXPECT_NE(message.find("walk.bag"), std::string::npos) << message;
}

#else

using ros1::CameraInfoMsg;
using ros1::ImageMsg;
using CompressedMsg = ros1::CompressedImageMsg;

constexpr double kFolderDepthScale = 5000;  // TumWriter's raw units per metre

// The shared folder: 8 frames of 160x120 with one moving object, written as `synth` writes it.
// Seed 2's object is segmented from the second frame on (seed 3's only in the last two of the
// eight, and with scores.long_baseline_frames in none).
struct SynthFolder {
  ff::testing::TempDir tmp;
  std::string dir;
  CameraIntrinsics camera;
  std::vector<FrameEntry> entries;
  SynthFolder() {
    synth::SynthConfig c;
    c.seed = 2;
    c.frames = 8;
    c.width = 160;
    c.height = 120;
    c.objects = 1;
    const synth::SyntheticScene scene(c);
    dir = (tmp.path() / "seq").string();
    synth::writeSequence(scene, dir);
    const TumSequence seq = TumSequence::open(dir);
    camera = seq.camera();
    for (size_t i = 0; i < seq.size(); ++i) entries.push_back(seq.entry(i));
  }
  std::string groundtruth() const { return dir + "/groundtruth.txt"; }
};

const SynthFolder& folder() {
  static const SynthFolder f;
  return f;
}

ros::Time rosTime(double t) {
  const auto us = static_cast<int64_t>(std::llround(t * 1e6));
  return ros::Time(static_cast<uint32_t>(us / 1000000), static_cast<uint32_t>(us % 1000000) * 1000);
}

struct BagSpec {
  std::string color = "rgb8";    // rgb8 bgr8 mono8 png jpeg, or another encoding to refuse
  std::string depth = "16UC1";   // 16UC1 32FC1
  uint32_t compression = rosbag::compression::Uncompressed;
  std::string color_topic = "/camera/rgb/image_color";
  std::string depth_topic = "/camera/depth/image";
  bool write_color = true, write_depth = true, camera_info = true;
  int depth_width = 0;           // 0: the folder's
  int swap_stamps = -1;          // colour stamps of messages k and k + 1 swapped
  std::vector<double> distortion = std::vector<double>(5, 0.0);  // CameraInfo's plumb-bob k1 k2 p1 p2 k3
};

// `stamp` in the header, `received` as the bag's time (the order messages are read in).
void writeImage(rosbag::Bag& bag, const std::string& topic, const ros::Time& stamp, const ros::Time& received,
                const cv::Mat& m, const std::string& encoding) {
  ImageMsg msg;
  msg.header.stamp = stamp;
  msg.height = m.rows;
  msg.width = m.cols;
  msg.encoding = encoding;
  msg.step = static_cast<uint32_t>(m.cols * m.elemSize());
  msg.data.assign(m.data, m.data + m.total() * m.elemSize());
  bag.write(topic, received, msg);
}

void writeColor(rosbag::Bag& bag, const BagSpec& spec, const ros::Time& stamp, const ros::Time& received,
                const cv::Mat& bgr) {
  if (spec.color == "png" || spec.color == "jpeg") {
    CompressedMsg msg;
    msg.header.stamp = stamp;
    msg.format = spec.color == "png" ? "rgb8; png compressed bgr8" : "jpeg";
    std::vector<uint8_t> bytes;
    cv::imencode(spec.color == "png" ? ".png" : ".jpg", bgr, bytes);
    msg.data.assign(bytes.begin(), bytes.end());
    bag.write(spec.color_topic, received, msg);
    return;
  }
  cv::Mat m;
  if (spec.color == "rgb8") cv::cvtColor(bgr, m, cv::COLOR_BGR2RGB);
  else if (spec.color == "mono8") cv::cvtColor(bgr, m, cv::COLOR_BGR2GRAY);
  else m = bgr;
  writeImage(bag, spec.color_topic, stamp, received, m, spec.color);
}

void writeDepth(rosbag::Bag& bag, const BagSpec& spec, const ros::Time& stamp, const cv::Mat& d16) {
  cv::Mat m = d16;
  if (spec.depth_width > 0) cv::resize(d16, m, cv::Size(spec.depth_width, d16.rows * spec.depth_width / d16.cols), 0,
                                       0, cv::INTER_NEAREST);
  if (spec.depth == "32FC1") {
    cv::Mat metres;
    m.convertTo(metres, CV_32F, 1.0 / kFolderDepthScale);  // as makeRgbdFrame converts the folder's PNG
    metres.setTo(std::numeric_limits<float>::quiet_NaN(), m == 0);  // ROS drivers' "no measurement"
    m = metres;
  }
  writeImage(bag, spec.depth_topic, stamp, stamp, m, spec.depth);
}

// The folder's frames as a bag.
void writeBag(const std::string& path, const BagSpec& spec) {
  const SynthFolder& f = folder();
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(static_cast<rosbag::CompressionType>(spec.compression));
  if (spec.camera_info) {
    CameraInfoMsg info;
    info.header.stamp = rosTime(f.entries.front().rgb_timestamp);
    info.width = f.camera.width;
    info.height = f.camera.height;
    info.distortion_model = "plumb_bob";
    info.D.assign(spec.distortion.begin(), spec.distortion.end());
    info.K = {f.camera.fx, 0, f.camera.cx, 0, f.camera.fy, f.camera.cy, 0, 0, 1};
    bag.write("/camera/rgb/camera_info", info.header.stamp, info);
  }
  for (size_t i = 0; i < f.entries.size(); ++i) {
    const FrameEntry& e = f.entries[i];
    size_t stamp_of = i;
    if (spec.swap_stamps >= 0 && i == size_t(spec.swap_stamps)) stamp_of = i + 1;
    if (spec.swap_stamps >= 0 && i == size_t(spec.swap_stamps) + 1) stamp_of = i - 1;
    const ros::Time t_color = rosTime(f.entries[stamp_of].rgb_timestamp), t_depth = rosTime(e.depth_timestamp);
    if (spec.write_color)
      writeColor(bag, spec, t_color, rosTime(e.rgb_timestamp), cv::imread(e.rgb_path, cv::IMREAD_UNCHANGED));
    if (spec.write_depth) writeDepth(bag, spec, t_depth, cv::imread(e.depth_path, cv::IMREAD_UNCHANGED));
  }
  bag.close();
}

// Options under which a bag of the folder's frames reads as the folder does.
SequenceOptions bagOptions() {
  SequenceOptions o;
  o.bag.depth_scale = kFolderDepthScale;
  o.bag.groundtruth = folder().groundtruth();
  return o;
}

std::string compressionName(uint32_t c) {
  return c == rosbag::compression::BZ2 ? "bz2" : c == rosbag::compression::LZ4 ? "lz4" : "none";
}

void expectSameFrames(FrameSource& bag, FrameSource& dir, const std::string& color, const std::string& what) {
  ASSERT_EQ(bag.remaining(), dir.remaining()) << what;
  EXPECT_EQ(bag.camera().fx, dir.camera().fx);
  EXPECT_EQ(bag.camera().width, dir.camera().width);
  while (auto a = dir.next()) {
    const auto b = bag.next();
    ASSERT_TRUE(b.has_value()) << what;
    EXPECT_EQ(b->timestamp, a->timestamp) << what;
    EXPECT_EQ(b->depth_timestamp, a->depth_timestamp) << what;
    cv::Mat expected = a->color;
    if (color == "mono8") {
      cv::cvtColor(a->color, expected, cv::COLOR_BGR2GRAY);
      cv::cvtColor(expected, expected, cv::COLOR_GRAY2BGR);
    }
    EXPECT_EQ(cv::norm(b->color, expected, cv::NORM_INF), 0) << what;
    EXPECT_EQ(cv::norm(b->depth, a->depth, cv::NORM_INF), 0) << what;
  }
  EXPECT_FALSE(bag.next().has_value()) << what;
}

TEST(BagSource, EveryEncodingAndCompressionReadsAsTheFolder) {
  ff::testing::TempDir tmp;
  const std::vector<std::string> colors = {"rgb8", "bgr8", "mono8", "png"}, depths = {"16UC1", "32FC1"};
  const std::vector<uint32_t> compressions = {rosbag::compression::Uncompressed, rosbag::compression::BZ2,
                                              rosbag::compression::LZ4};
  // Every colour encoding with every compression; the depth encoding alternates, so each colour
  // encoding and each compression meets both depth encodings.
  for (size_t i = 0; i < colors.size(); ++i)
    for (size_t k = 0; k < compressions.size(); ++k) {
      const std::string& color = colors[i];
      const std::string& depth = depths[(i + k) % 2];
      const uint32_t compression = compressions[k];
      const std::string what = color + " " + depth + " " + compressionName(compression);
      const std::string path = (tmp.path() / (color + depth + compressionName(compression) + ".bag")).string();
      BagSpec spec;
      spec.color = color;
      spec.depth = depth;
      spec.compression = compression;
      writeBag(path, spec);
      BagSource bag(path, bagOptions());
      TumFolderSource dir(TumSequence::open(folder().dir));
      expectSameFrames(bag, dir, color, what);
      ASSERT_NE(bag.groundtruth(), nullptr);
    }
}

TEST(BagSource, JpegColourIsWhatOpenCvDecodesFromIt) {
  ff::testing::TempDir tmp;
  const std::string path = (tmp.path() / "jpeg.bag").string();
  BagSpec spec;
  spec.color = "jpeg";
  writeBag(path, spec);
  BagSource bag(path, bagOptions());
  for (const FrameEntry& e : folder().entries) {
    const auto frame = bag.next();
    ASSERT_TRUE(frame.has_value());
    std::vector<uint8_t> bytes;
    const cv::Mat png = cv::imread(e.rgb_path, cv::IMREAD_UNCHANGED);
    cv::imencode(".jpg", png, bytes);
    EXPECT_EQ(cv::norm(frame->color, cv::imdecode(bytes, cv::IMREAD_UNCHANGED), cv::NORM_INF), 0);
    // Lossy, yet close to the lossless frame: mean error of a few levels.
    EXPECT_LT(cv::norm(frame->color, png, cv::NORM_L1) / png.total() / 3, 4.0);
  }
}

TEST(BagSource, TopicsAndRangeAreHonoured) {
  ff::testing::TempDir tmp;
  const std::string path = (tmp.path() / "topics.bag").string();
  BagSpec spec;
  spec.color_topic = "/cam/front/color";
  spec.depth_topic = "/cam/front/depth";
  spec.camera_info = false;
  writeBag(path, spec);
  SequenceOptions o = bagOptions();
  o.camera = "100,100,79.5,59.5,160,120";
  BagSource bag(path, o, FrameRange{2, 5});  // the only colour and depth topics, found by name
  EXPECT_EQ(bag.reader().colorTopic(), "/cam/front/color");
  EXPECT_EQ(bag.reader().depthTopic(), "/cam/front/depth");
  EXPECT_EQ(bag.camera().fx, 100);
  EXPECT_EQ(bag.remaining(), 4u);
  EXPECT_EQ(bag.next()->timestamp, folder().entries[2].rgb_timestamp);
  o.bag.rgb_topic = "/cam/front/missing";
  const std::string message = inputErrorOf([&] { BagSource bag(path, o); });
  EXPECT_NE(message.find("--rgb-topic /cam/front/missing"), std::string::npos) << message;
  EXPECT_NE(message.find("/cam/front/color (sensor_msgs/Image)"), std::string::npos) << message;
}

TEST(BagSource, CameraInfoDistortionIsUndistortedAsAFoldersCameraTxt) {
  ff::testing::TempDir tmp;
  const std::vector<double> d = {0.08, -0.15, 0.001, -0.002, 0.05};
  const fs::path dir = tmp.path() / "distorted";
  fs::copy(folder().dir, dir, fs::copy_options::recursive);
  const CameraIntrinsics& c = folder().camera;
  std::ofstream camera_txt(dir / "camera.txt");
  camera_txt.precision(17);
  camera_txt << c.fx << ' ' << c.fy << ' ' << c.cx << ' ' << c.cy << ' ' << c.width << ' ' << c.height;
  for (double k : d) camera_txt << ' ' << k;
  camera_txt.close();
  const std::string path = (tmp.path() / "distorted.bag").string();
  BagSpec spec;
  spec.distortion = d;
  writeBag(path, spec);
  BagSource bag(path, bagOptions());
  TumFolderSource folder_source(TumSequence::open(dir.string()));
  EXPECT_DOUBLE_EQ(bag.reader().camera().distortion.k1, 0.08);
  cv::Mat mask(c.height, c.width, CV_8U);
  cv::randu(mask, 0, 256);
  EXPECT_EQ(cv::norm(bag.toRawPixels(mask), folder_source.toRawPixels(mask), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(bag.toRawPixels(mask), mask, cv::NORM_INF), 0) << "the distortion should move pixels";
  expectSameFrames(bag, folder_source, "rgb8", "distorted");
}

using testing::RunOutput;
using testing::expectSameRun;
using testing::runOn;

TEST(BagSource, RunAndConvertedRunGiveTheFoldersTrajectoryAndMasks) {
  ff::testing::TempDir tmp;
  TumFolderSource dir(TumSequence::open(folder().dir));
  const RunOutput reference = runOn(dir);
  size_t dynamic = 0;
  for (const cv::Mat& m : reference.masks) dynamic += cv::countNonZero(m);
  EXPECT_GT(dynamic, 0u) << "the scene's object should be segmented somewhere";

  BagSpec a;  // rgb8, 16UC1 in the folder's units, lz4
  a.compression = rosbag::compression::LZ4;
  BagSpec b;  // png, 32FC1 metres, bz2
  b.color = "png";
  b.depth = "32FC1";
  b.compression = rosbag::compression::BZ2;
  for (const BagSpec& spec : {a, b}) {
    const std::string what = spec.color + " " + spec.depth;
    const std::string path = (tmp.path() / (spec.color + ".bag")).string();
    writeBag(path, spec);
    BagSource bag(path, bagOptions());
    expectSameRun(reference, runOn(bag), "bag " + what);

    const std::string converted = (tmp.path() / ("converted_" + spec.color)).string();
    const BagConversion c = convertBagToTum(path, converted, bagOptions());
    EXPECT_EQ(c.frames, folder().entries.size());
    EXPECT_EQ(c.saturated_pixels, 0u);
    TumFolderSource again(TumSequence::open(converted));
    expectSameRun(reference, runOn(again), "converted " + what);
    ASSERT_NE(again.groundtruth(), nullptr);
  }
}

TEST(BagSource, ConvertWritesTumDepthAndTheCamera) {
  ff::testing::TempDir tmp;
  const std::string path = (tmp.path() / "mm.bag").string();
  writeBag(path, BagSpec{});
  SequenceOptions o;  // 16UC1 read as millimetres (ROS drivers' unit): TUM's 5000 per metre is 5 per unit
  const std::string out = (tmp.path() / "out").string();
  convertBagToTum(path, out, o);
  const TumSequence seq = TumSequence::open(out);
  EXPECT_EQ(seq.camera().fx, folder().camera.fx);
  EXPECT_EQ(seq.camera().height, folder().camera.height);
  const cv::Mat original = cv::imread(folder().entries[0].depth_path, cv::IMREAD_UNCHANGED);
  const cv::Mat written = cv::imread(seq.entry(0).depth_path, cv::IMREAD_UNCHANGED);
  cv::Mat expected;
  original.convertTo(expected, CV_16U, 5.0);
  EXPECT_EQ(cv::norm(written, expected, cv::NORM_INF), 0);
  EXPECT_NE(inputErrorOf([&] { convertBagToTum(path, out, o); }).find("not empty"), std::string::npos);
}

struct BadBag {
  std::string what;
  BagSpec spec;
  std::vector<std::string> expected;  // in the message
  bool on_read = false;               // refused when the frame is read, not when the bag is opened
};

TEST(BagSource, BadBagsGiveInputErrorsThatSayWhatIsWrong) {
  ff::testing::TempDir tmp;
  std::vector<BadBag> cases;
  BagSpec no_images;
  no_images.write_color = no_images.write_depth = false;
  cases.push_back({"no image topics", no_images, {"no image topics", "/camera/rgb/camera_info"}});
  BagSpec only_color;
  only_color.write_depth = false;
  cases.push_back({"only colour", only_color, {"no depth image topic", "--depth-topic"}});
  BagSpec small_depth;
  small_depth.depth_width = 80;
  cases.push_back({"depth of another size", small_depth, {"/camera/depth/image#0", "80x60", "160x120"}, true});
  BagSpec yuv;
  yuv.color = "yuv422";
  cases.push_back({"unknown encoding", yuv, {"/camera/rgb/image_color", "yuv422", "rgb8"}});
  BagSpec unsorted;
  unsorted.swap_stamps = 3;
  cases.push_back({"unsorted stamps", unsorted, {"/camera/rgb/image_color message 4", "not after"}});
  BagSpec no_camera;
  no_camera.camera_info = false;
  cases.push_back({"no camera", no_camera, {"no camera intrinsics", "--camera"}});
  for (const BadBag& c : cases) {
    const std::string path = (tmp.path() / (std::to_string(&c - cases.data()) + ".bag")).string();
    writeBag(path, c.spec);
    const std::string message = inputErrorOf([&] {
      BagSource bag(path, bagOptions());
      if (c.on_read) bag.next();
    });
    EXPECT_NE(message.find(path), std::string::npos) << c.what << ": " << message;
    for (const auto& part : c.expected) EXPECT_NE(message.find(part), std::string::npos) << c.what << ": " << message;
  }
}

TEST(BagSource, TruncatedOrForeignFilesAreRefusedByName) {
  ff::testing::TempDir tmp;
  const std::string good = (tmp.path() / "good.bag").string();
  writeBag(good, BagSpec{});
  const auto size = fs::file_size(good);
  for (const double keep : {0.0, 0.01, 0.5, 0.99}) {
    const std::string cut = (tmp.path() / ("cut" + std::to_string(int(keep * 100)) + ".bag")).string();
    fs::copy_file(good, cut);
    fs::resize_file(cut, static_cast<uintmax_t>(size * keep));
    const std::string message = inputErrorOf([&] {
      BagSource bag(cut, bagOptions());
      while (bag.next()) {
      }
    });
    EXPECT_NE(message.find(cut), std::string::npos) << keep << ": " << message;
  }
  const std::string text = (tmp.path() / "notes.bag").string();
  std::ofstream(text) << "not a bag\n";
  EXPECT_NE(inputErrorOf([&] { BagSource bag(text, bagOptions()); }).find("notes.bag"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { openFrameSource((tmp.path() / "absent.bag").string(), bagOptions()); })
                .find("does not exist"),
            std::string::npos);
}

TEST(BagSource, OpenFrameSourceOpensBags) {
  ff::testing::TempDir tmp;
  const std::string path = (tmp.path() / "walk.bag").string();
  writeBag(path, BagSpec{});
  const auto source = openFrameSource(path, bagOptions(), FrameRange{1, -1});
  EXPECT_EQ(source->name(), path);
  EXPECT_EQ(source->remaining(), folder().entries.size() - 1);
}


// Issue 30: `convert` gets the `run` treatment. A bag of the folder's frames repeated `frames`
// times (stamps 1/30 s apart, LZ4), long enough for a signal to arrive while it converts.
void writeLongBag(const std::string& path, size_t frames) {
  const SynthFolder& f = folder();
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  BagSpec spec;
  const double t0 = f.entries.front().rgb_timestamp;
  for (size_t i = 0; i < frames; ++i) {
    const FrameEntry& e = f.entries[i % f.entries.size()];
    const ros::Time t = rosTime(t0 + static_cast<double>(i) / 30.0);
    writeColor(bag, spec, t, t, cv::imread(e.rgb_path, cv::IMREAD_UNCHANGED));
    writeDepth(bag, spec, t, cv::imread(e.depth_path, cv::IMREAD_UNCHANGED));
  }
  bag.close();
}

// A bag whose frame `bad` has a depth image of half the size (it fails when read).
void writeBagWithBadFrame(const std::string& path, size_t bad) {
  const SynthFolder& f = folder();
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  BagSpec spec, small;
  small.depth_width = f.camera.width / 2;
  for (size_t i = 0; i < f.entries.size(); ++i) {
    const FrameEntry& e = f.entries[i];
    const ros::Time t = rosTime(e.rgb_timestamp);
    writeColor(bag, spec, t, t, cv::imread(e.rgb_path, cv::IMREAD_UNCHANGED));
    writeDepth(bag, i == bad ? small : spec, t, cv::imread(e.depth_path, cv::IMREAD_UNCHANGED));
  }
  bag.close();
}

std::string convertCommand(const std::string& bag, const std::string& out, const std::string& more = "") {
  return std::string(FLOWFUSION_APP_PATH) + " convert '" + bag + "' '" + out + "' --camera 100,100,79.5,59.5,160,120" +
         more;
}

size_t filesIn(const fs::path& dir) {
  return fs::is_directory(dir) ? static_cast<size_t>(std::distance(fs::directory_iterator(dir), {})) : 0;
}

// What a stopped conversion leaves: the frames written, each listed once, marked partial.
void expectMarkedPartial(const fs::path& out, const std::string& reason, size_t min_frames, size_t max_frames) {
  const nlohmann::json summary = readJsonFile((out / "summary.json").string());
  EXPECT_FALSE(summary["complete"].get<bool>()) << summary.dump();
  EXPECT_NE(summary["stop_reason"].get<std::string>().find(reason), std::string::npos) << summary.dump();
  const size_t frames = summary["frames"].get<size_t>();
  EXPECT_GE(frames, min_frames);
  EXPECT_LE(frames, max_frames);
  EXPECT_EQ(filesIn(out / "rgb"), frames);
  EXPECT_EQ(filesIn(out / "depth"), frames);
  EXPECT_EQ(TumSequence::open(out.string()).size(), frames) << "rgb.txt and depth.txt list the frames written";
}

void stopsWith(const std::string& signal, int status) {
  ff::testing::TempDir tmp;
  const std::string bag = (tmp.path() / "long.bag").string(), out = (tmp.path() / "out").string();
  constexpr size_t kFrames = 600;
  writeLongBag(bag, kFrames);
  const std::string script = convertCommand(bag, out) + " & pid=$!; for i in $(seq 600); do n=$(ls " + out +
                             "/rgb 2>/dev/null | wc -l); [ \"$n\" -ge 3 ] && break; sleep 0.02; done; kill -" +
                             signal + " $pid; wait $pid";
  const auto r = ff::testing::runShell(script);
  EXPECT_EQ(r.status, status) << r.output;
  EXPECT_NE(r.output.find("convert stopped after"), std::string::npos) << r.output;
  expectMarkedPartial(out, "SIG" + signal, 3, kFrames - 1);
  // The rerun replaces it with the whole conversion.
  const auto again = ff::testing::runShell(convertCommand(bag, out, " --overwrite"));
  EXPECT_EQ(again.status, 0) << again.output;
  const nlohmann::json summary = readJsonFile(out + "/summary.json");
  EXPECT_TRUE(summary["complete"].get<bool>());
  EXPECT_EQ(summary["frames"].get<size_t>(), kFrames);
  EXPECT_EQ(TumSequence::open(out).size(), kFrames);
}

TEST(BagConvert, SigintLeavesAMarkedPartialResultAndARerunWorks) { stopsWith("INT", 130); }

TEST(BagConvert, SigtermDoesTheSame) { stopsWith("TERM", 143); }

TEST(BagConvert, AFrameFailingMidBagLeavesAMarkedPartialResult) {
  ff::testing::TempDir tmp;
  const std::string bag = (tmp.path() / "bad5.bag").string();
  writeBagWithBadFrame(bag, 5);
  const fs::path out = tmp.path() / "out";
  const auto r = ff::testing::runShell(convertCommand(bag, out.string()));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("80x60"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the 5 frames before it are in " + out.string() + ", marked partial"), std::string::npos)
      << r.output;
  expectMarkedPartial(out, "80x60", 5, 5);
}

TEST(BagConvert, AnEarlyFailureLeavesNothingAndTheRerunWorks) {
  ff::testing::TempDir tmp;
  const std::string bad = (tmp.path() / "bad0.bag").string(), good = (tmp.path() / "good.bag").string();
  writeBagWithBadFrame(bad, 0);
  writeBag(good, BagSpec{});
  const fs::path out = tmp.path() / "out";
  const auto r = ff::testing::runShell(convertCommand(bad, out.string()));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_FALSE(fs::exists(out)) << "nothing to keep, nothing to block the rerun";
  // Ground truth and options are checked before the first frame: nothing is written.
  const std::string missing = (tmp.path() / "missing.txt").string();
  for (const std::string& more : {" --groundtruth " + missing, std::string(" --depth-scale 1e-30"),
                                 std::string(" --depth-scale inf"), std::string(" --depth-scale nan")}) {
    const auto early = ff::testing::runShell(convertCommand(good, out.string(), more));
    EXPECT_EQ(early.status, 2) << more << ": " << early.output;
    EXPECT_NE(early.output.find(more.substr(1, more.find(' ', 1) - 1)), std::string::npos) << early.output;
    EXPECT_FALSE(fs::exists(out)) << more;
  }
  const auto rerun = ff::testing::runShell(convertCommand(good, out.string(), " --groundtruth " + folder().groundtruth()));
  EXPECT_EQ(rerun.status, 0) << rerun.output;
  EXPECT_TRUE(readJsonFile((out / "summary.json").string())["complete"].get<bool>());
  EXPECT_TRUE(fs::exists(out / "groundtruth.txt"));
}

TEST(BagConvert, ABagThatIsAFolderOrAFifoOrMixesImageTypesSaysSo) {
  ff::testing::TempDir tmp;
  const fs::path folder_bag = tmp.path() / "walk.bag", fifo = tmp.path() / "pipe.bag";
  fs::create_directories(folder_bag);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(inputErrorOf([&] { openFrameSource(folder_bag.string(), bagOptions()); }).find("is a folder, not a ROS bag"),
            std::string::npos);
  EXPECT_NE(inputErrorOf([&] { openFrameSource(fifo.string(), bagOptions()); }).find("is not a regular file"),
            std::string::npos);
  // One colour topic with both sensor_msgs/Image and CompressedImage messages.
  const std::string mixed = (tmp.path() / "mixed.bag").string();
  {
    const SynthFolder& f = folder();
    rosbag::Bag bag(mixed, rosbag::bagmode::Write);
    BagSpec raw, png;
    png.color = "png";
    for (size_t i = 0; i < f.entries.size(); ++i) {
      const FrameEntry& e = f.entries[i];
      const ros::Time t = rosTime(e.rgb_timestamp);
      writeColor(bag, i % 2 ? png : raw, t, t, cv::imread(e.rgb_path, cv::IMREAD_UNCHANGED));
      writeDepth(bag, raw, t, cv::imread(e.depth_path, cv::IMREAD_UNCHANGED));
    }
    bag.close();
  }
  const std::string message = inputErrorOf([&] { BagSource bag(mixed, bagOptions()); });
  EXPECT_NE(message.find("/camera/rgb/image_color message 1 does not decode as the topic's sensor_msgs/Image"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("mixes sensor_msgs/Image and CompressedImage"), std::string::npos) << message;
}

#endif  // FLOWFUSION_HAVE_ROSBAG

}  // namespace
}  // namespace ff

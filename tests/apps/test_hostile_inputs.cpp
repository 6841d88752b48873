// The `flowfusion` executable against the hostile inputs and faults of issue 16: every case ends
// with exit status 2 and a message naming the file or setting, never an abort (134), an internal
// error (3) or a silent exit 0, and leaves no short or empty file under a final name.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

using testing::CommandResult;
using testing::makeTinySequence;
using testing::runFlowfusion;

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// Every regular file under dir: none empty, none a leftover temporary of the atomic writer.
void expectNoEmptyOrTemporaryFiles(const fs::path& dir) {
  if (!fs::exists(dir)) return;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    EXPECT_GT(e.file_size(), 0u) << e.path();
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  }
}

void expectError(const CommandResult& r, const std::string& needle) {
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(needle), std::string::npos) << "'" << needle << "' not in: " << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
}

// Case 1, on a real full disk: a 64 KiB tmpfs (root only; skipped otherwise).
TEST(HostileInputs, FullDiskIsAnErrorAndLeavesNoEmptyFiles) {
  testing::TempDir tmp;
  if (::mount("tmpfs", tmp.str().c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (not root); FileSizeLimit covers the same path";
  const fs::path out = tmp.path() / "synth";
  const auto r = runFlowfusion("synth " + q(out) + " --frames 30 --width 96 --height 72 --seed 2");
  expectError(r, "No space left on device");
  EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
  expectNoEmptyOrTemporaryFiles(out);
  ::umount(tmp.str().c_str());
}

// Case 1 for run: masks fill the 64 KiB (16 pages) before the trajectory is written.
TEST(HostileInputs, RunOnAFullDiskIsAnErrorAndLeavesNoEmptyFiles) {
  testing::TempDir tmp;
  const fs::path seq = tmp.path() / "seq", disk = tmp.path() / "disk";
  ASSERT_EQ(runFlowfusion("synth " + q(seq) + " --width 160 --height 120 --frames 30 --seed 3").status, 0);
  fs::create_directories(disk);
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (not root)";
  const auto r = runFlowfusion("run " + q(seq) + " --quiet --out " + q(disk / "out"));
  expectError(r, "No space left on device");
  expectNoEmptyOrTemporaryFiles(disk / "out");
  ::umount(disk.c_str());
}

// Case 1 without root: a file-size limit makes every write past 16 KiB fail (EFBIG).
TEST(HostileInputs, FileSizeLimitIsAnErrorAndLeavesNoEmptyFiles) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "synth";
  const auto r = runFlowfusion("synth " + q(out) + " --frames 3 --width 320 --height 240 --seed 2",
                               "trap '' XFSZ; ulimit -f 16");
  expectError(r, "File too large");
  expectNoEmptyOrTemporaryFiles(out);
}

size_t filesIn(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
}

// Case 2: augment into its own input (or into a folder inside it) is refused, --overwrite or not.
TEST(HostileInputs, AugmentIntoItsInputIsRefused) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  const auto before = fs::last_write_time(seq / "rgb" / "1.000000.png");
  expectError(runFlowfusion("augment " + q(seq) + " " + q(seq) + " --overwrite"), "is the input sequence");
  expectError(runFlowfusion("augment " + q(seq) + " " + q(seq / "aug")), "lies inside the input sequence");
  expectError(runFlowfusion("augment " + q(seq) + " " + q(tmp.path()) + " --overwrite"),
              "contains the input sequence");
  EXPECT_EQ(fs::last_write_time(seq / "rgb" / "1.000000.png"), before);
  EXPECT_EQ(filesIn(seq / "rgb"), 2u);
  EXPECT_FALSE(fs::exists(seq / "aug"));
}

// Case 3: --overwrite removes the previous run's files (its manifest) and only those.
TEST(HostileInputs, OverwriteLeavesNoStaleFilesAndKeepsTheUsers) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "synth";
  const std::string synth = "synth " + q(out) + " --width 64 --height 48 --seed 4 --objects 1 ";
  ASSERT_EQ(runFlowfusion(synth + "--frames 12").status, 0);
  EXPECT_EQ(filesIn(out / "masks"), 12u);
  std::ofstream(out / "my_notes.txt") << "the user's";
  ASSERT_EQ(runFlowfusion(synth + "--frames 3 --overwrite").status, 0);
  EXPECT_EQ(filesIn(out / "masks"), 3u);
  EXPECT_EQ(filesIn(out / "rgb"), 3u);
  EXPECT_EQ(filesIn(out / "depth"), 3u);
  EXPECT_TRUE(fs::exists(out / "my_notes.txt"));
  expectNoEmptyOrTemporaryFiles(out);
}

// Case 2 for run: the sequence's ground-truth masks are never replaced by estimates.
TEST(HostileInputs, RunIntoItsInputIsRefused) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  fs::create_directories(seq / "masks");
  cv::imwrite((seq / "masks" / "1.000000.png").string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(255)));
  const auto before = fs::last_write_time(seq / "masks" / "1.000000.png");
  expectError(runFlowfusion("run " + q(seq) + " --out " + q(seq) + " --overwrite --quiet"), "is the input sequence");
  expectError(runFlowfusion("run " + q(seq) + " --out " + q(seq / "out") + " --quiet"), "lies inside the input");
  EXPECT_EQ(fs::last_write_time(seq / "masks" / "1.000000.png"), before);
  EXPECT_EQ(filesIn(seq / "masks"), 1u);
  EXPECT_FALSE(fs::exists(seq / "out"));
  EXPECT_FALSE(fs::exists(seq / "trajectory.txt"));
}

// Case 3 for run, and --overwrite refusing another command's output.
TEST(HostileInputs, RunOverwriteRemovesOnlyItsOwnEarlierFiles) {
  testing::TempDir tmp;
  const fs::path seq = tmp.path() / "seq", out = tmp.path() / "out";
  ASSERT_EQ(runFlowfusion("synth " + q(seq) + " --width 160 --height 120 --frames 6 --seed 3").status, 0);
  ASSERT_EQ(runFlowfusion("run " + q(seq) + " --quiet --no-map --out " + q(out)).status, 0);
  EXPECT_EQ(filesIn(out / "masks"), 6u);
  std::ofstream(out / "my_notes.txt") << "the user's";
  const auto r = runFlowfusion("run " + q(seq) + " --quiet --no-map --frames 0:1 --overwrite --out " + q(out));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(filesIn(out / "masks"), 2u);
  EXPECT_TRUE(fs::exists(out / "my_notes.txt"));
  expectNoEmptyOrTemporaryFiles(out);
  // A run may not overwrite a synthetic sequence (another command's output) with --overwrite.
  const fs::path other = makeTinySequence(tmp.path() / "other");
  expectError(runFlowfusion("run " + q(other) + " --quiet --overwrite --out " + q(seq)),
              "holds the output of 'flowfusion synth'");
  EXPECT_EQ(filesIn(seq / "rgb"), 6u);
}

// Case 11: an empty output folder name.
TEST(HostileInputs, EmptyOutputNameIsRefused) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  expectError(runFlowfusion("run " + q(seq) + " --out ''"), "output folder name is empty");
  expectError(runFlowfusion("synth '' --frames 2"), "output folder name is empty");
}

// Case 6.
TEST(HostileInputs, SupervoxelResolutionThatAbortsPclIsRefused) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  const auto r = runFlowfusion("run " + q(seq) + " --out " + q(tmp.path() / "out") +
                               " --set clustering.backend=supervoxel --set clustering.voxel_resolution=1e-9");
  expectError(r, "voxel_resolution must be 0.001 to 1 metre, got 1e-09");
  EXPECT_FALSE(fs::exists(tmp.path() / "out" / "trajectory.txt"));
}

// Case 7: integers that wrapped, values without a range, unbounded synth.
TEST(HostileInputs, NumbersThatWrapOrExceedTheirRangeAreRefused) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  const std::string run = "run " + q(seq) + " --out " + q(tmp.path() / "out") + " ";
  expectError(runFlowfusion(run + "--set odometry.levels=4294967300"), "'odometry.levels': 4294967300 is out of range");
  expectError(runFlowfusion(run + "--set odometry.max_iterations=4294967297"), "'odometry.max_iterations'");
  expectError(runFlowfusion(run + "--camera 50,50,1e300,23.5,64,48"), "principal point");
  expectError(runFlowfusion(run + "--camera 1e-300,50,31.5,23.5,64,48"), "focal lengths");
  EXPECT_FALSE(fs::exists(tmp.path() / "out"));

  const fs::path synth = tmp.path() / "synth";
  expectError(runFlowfusion("synth " + q(synth) + " --seed -1"), "--seed");
  expectError(runFlowfusion("synth " + q(synth) + " --set seed=-1"), "'seed': -1 is out of range");
  expectError(runFlowfusion("synth " + q(synth) + " --frames 1000000000"), "at most 100000");
  EXPECT_FALSE(fs::exists(synth));
}

TEST(HostileInputs, RpeDeltaLongerThanTheTrajectoryIsRefused) {
  testing::TempDir tmp;
  const fs::path traj = tmp.path() / "t.txt";
  std::ofstream out(traj);
  for (int k = 0; k < 20; ++k) out << 1 + 0.1 * k << " " << 0.01 * k << " 0 0 0 0 0 1\n";
  out.close();
  expectError(runFlowfusion("eval rpe " + q(traj) + " " + q(traj) + " --delta 1e300"), "--delta");
  expectError(runFlowfusion("eval rpe " + q(traj) + " " + q(traj) + " --delta nan"), "--delta");
}

// Case 8: user errors that were internal errors.
TEST(HostileInputs, ConfigFolderHugePngAndHugePlyAreInputErrors) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  expectError(runFlowfusion("run " + q(seq) + " --out " + q(tmp.path() / "out") + " --config " + q(tmp.path())),
              tmp.str() + ": is a folder");

  // A colour frame whose PNG header declares 100000x100000 (refused from the header alone).
  const fs::path png = seq / "rgb" / "1.000000.png";
  std::fstream f(png, std::ios::in | std::ios::out | std::ios::binary);
  const unsigned char size[8] = {0, 1, 0x86, 0xa0, 0, 1, 0x86, 0xa0};
  f.seekp(16);
  f.write(reinterpret_cast<const char*>(size), 8);
  f.close();
  expectError(runFlowfusion("run " + q(seq) + " --out " + q(tmp.path() / "out2")), "100000x100000");

  const fs::path ply = tmp.path() / "huge.ply";
  std::ofstream(ply) << "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty double x\n"
                        "property double y\nproperty double z\nend_header\n"
                     << std::string(240, '\0');
  expectError(runFlowfusion("eval map " + q(ply) + " " + q(ply)), "PLY header declares more elements");
}

// Case 11: huge timestamps, garbage lines, a folder for groundtruth.txt.
TEST(HostileInputs, HugeTimestampsGarbageLinesAndFoldersAreNamed) {
  testing::TempDir tmp;
  const fs::path seq = makeTinySequence(tmp.path() / "seq");
  const std::string run = "run " + q(seq) + " --out " + q(tmp.path() / "out");
  fs::create_directories(seq / "groundtruth.txt");
  expectError(runFlowfusion(run), "groundtruth.txt: is a folder, not a trajectory file");
  fs::remove(seq / "groundtruth.txt");

  std::ofstream(seq / "depth.txt") << "1.0 depth/1.000000.png\n1e300 depth/1.033333.png\n";
  expectError(runFlowfusion(run), "depth.txt:2: timestamp 1e+300 s is out of range");

  std::ofstream(seq / "depth.txt") << std::string(1 << 20, '\x01') << "\n";
  const auto r = runFlowfusion(run);
  expectError(r, "depth.txt:1: expected 'timestamp filename'");
  EXPECT_LT(r.output.size(), 600u);
  EXPECT_NE(r.output.find("(1048576 characters)"), std::string::npos) << r.output.substr(0, 600);
  EXPECT_FALSE(fs::exists(tmp.path() / "out" / "trajectory.txt"));
}

}  // namespace
}  // namespace ff

// Output folders: --overwrite removes exactly what an earlier command wrote (its manifest) and
// nothing of the user's; an output that is, contains or lies inside an input is refused.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

TEST(OutputFolder, OverwriteRemovesExactlyTheListedFiles) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "out";
  prepareOutputDir(out.string(), false);
  fs::create_directories(out / "masks");
  fs::create_directories(out / "preview");
  for (const char* name : {"trajectory.txt", "masks/1.000000.png", "masks/2.000000.png", "preview/preview_0.png"})
    writeFileAtomic((out / name).string(), "ours");
  writeFileAtomic((out / "trajectory.txt").string(), "ours again");  // listed once
  std::ofstream(out / "notes.txt") << "the user's";
  std::ofstream(out / "masks" / "hand_made.png") << "the user's";
  std::ofstream(tmp.path() / "outside.txt") << "the user's";
  std::ofstream(out / kManifestName, std::ios::app) << "../outside.txt\n"
                                                    << (tmp.path() / "outside.txt").string() << "\n";

  EXPECT_NE(testing::inputErrorOf([&] { prepareOutputDir(out.string(), false); }).find("--overwrite"), std::string::npos);
  prepareOutputDir(out.string(), true);
  EXPECT_FALSE(fs::exists(out / "trajectory.txt"));
  EXPECT_FALSE(fs::exists(out / "masks" / "1.000000.png"));
  EXPECT_FALSE(fs::exists(out / "preview"));  // emptied, so removed
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_TRUE(fs::exists(out / "masks" / "hand_made.png"));
  EXPECT_TRUE(fs::exists(tmp.path() / "outside.txt"));
  // The new manifest lists only what is written from now on.
  writeFileAtomic((out / "trajectory.txt").string(), "new");
  std::ifstream in(out / kManifestName);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(all.find("\ntrajectory.txt\n"), std::string::npos) << all;
  EXPECT_EQ(all.find("masks/"), std::string::npos) << all;
}

TEST(OutputFolder, OverwriteReplacesOnlyTheSameCommandsOutput) {
  testing::TempDir tmp;
  setOutputCommand("synth");
  prepareOutputDir(tmp.str(), false);
  writeFileAtomic((tmp.path() / "rgb.txt").string(), "ours");
  setOutputCommand("run");
  const std::string msg = testing::inputErrorOf([&] { prepareOutputDir(tmp.str(), true); });
  EXPECT_NE(msg.find("holds the output of 'flowfusion synth'"), std::string::npos) << msg;
  EXPECT_TRUE(fs::exists(tmp.path() / "rgb.txt"));
  setOutputCommand("synth");
  prepareOutputDir(tmp.str(), true);
  EXPECT_FALSE(fs::exists(tmp.path() / "rgb.txt"));
  setOutputCommand("");
}

TEST(OutputFolder, WithoutManifestOverwriteKeepsEverything) {
  testing::TempDir tmp;
  std::ofstream(tmp.path() / "a.txt") << "x";
  prepareOutputDir(tmp.str(), true);
  EXPECT_TRUE(fs::exists(tmp.path() / "a.txt"));
  EXPECT_NE(testing::inputErrorOf([] { prepareOutputDir("", true); }).find("output folder name is empty"), std::string::npos);
}

TEST(OutputFolder, OverlapWithAnInputIsRefused) {
  testing::TempDir tmp;
  const fs::path seq = tmp.path() / "seq";
  fs::create_directories(seq / "rgb");
  const std::string what = "the input sequence";
  EXPECT_NE(testing::inputErrorOf([&] { refuseOverlap(seq.string(), seq.string(), what); }).find(" is the input sequence"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorOf([&] { refuseOverlap((seq / "." / "rgb" / "..").string(), seq.string(), what); })
                .find(" is the input sequence"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorOf([&] { refuseOverlap(tmp.str(), seq.string(), what); }).find(" contains the input sequence"),
            std::string::npos);
  EXPECT_NE(testing::inputErrorOf([&] { refuseOverlap((seq / "out").string(), seq.string(), what); })
                .find(" lies inside the input sequence"),
            std::string::npos);
  fs::create_directory_symlink(seq, tmp.path() / "link");
  EXPECT_NE(testing::inputErrorOf([&] { refuseOverlap((tmp.path() / "link").string(), seq.string(), what); }).find(" is the"),
            std::string::npos);
  EXPECT_NO_THROW(refuseOverlap((tmp.path() / "seq2").string(), seq.string(), what));
  EXPECT_NO_THROW(refuseOverlap((tmp.path() / "out").string(), seq.string(), what));
}

TEST(OutputFolder, AFolderLockedElsewhereIsRefusedUntilReleased) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "out";
  fs::create_directories(out);
  // Another open file description, as another process would hold (flock locks are per open file).
  const int other = ::open(out.c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(other, 0);
  ASSERT_EQ(::flock(other, LOCK_EX | LOCK_NB), 0);
  const std::string msg = testing::inputErrorOf([&] { prepareOutputDir(out.string(), true); });
  EXPECT_NE(msg.find("another flowfusion command is writing into this output folder"), std::string::npos) << msg;
  EXPECT_NE(msg.find(out.string()), std::string::npos) << msg;
  EXPECT_TRUE(fs::is_empty(out)) << "nothing written before the lock";
  ::close(other);
  prepareOutputDir(out.string(), false);
  // This process holds it now: preparing it again is fine, another holder is refused.
  prepareOutputDir(out.string(), true);
  const int again = ::open(out.c_str(), O_RDONLY | O_DIRECTORY);
  EXPECT_NE(::flock(again, LOCK_EX | LOCK_NB), 0);
  releaseOutputDir();
  EXPECT_EQ(::flock(again, LOCK_EX | LOCK_NB), 0);
  ::close(again);
}

TEST(OutputFolder, AbandonLeavesNothingOfAFailedCommand) {
  testing::TempDir tmp;
  const fs::path out = tmp.path() / "new";
  prepareOutputDir(out.string(), false);
  writeFileAtomic((out / "rgb.txt").string(), "ours");
  abandonOutputDir();
  EXPECT_FALSE(fs::exists(out)) << "the folder it made goes too";
  // A folder that existed stays, with the user's files.
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "the user's";
  prepareOutputDir(out.string(), true);
  writeFileAtomic((out / "rgb.txt").string(), "ours");
  abandonOutputDir();
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_FALSE(fs::exists(out / "rgb.txt"));
  EXPECT_FALSE(fs::exists(out / kManifestName));
}

}  // namespace
}  // namespace ff

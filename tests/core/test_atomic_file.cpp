// The atomic writer: whole files or nothing under the final name, and a full disk is an error
// naming the file and the reason (a real 64 KiB tmpfs when the tests run as root, a file-size
// limit in a child process otherwise).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "testing/test_util.h"

namespace fs = std::filesystem;

namespace ff {
namespace {

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

size_t entries(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator{}));
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(AtomicFile, WritesAndReplacesWholeFilesWithoutLeavingTemporaries) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "a.txt";
  writeFileAtomic(p.string(), "first\n");
  writeFileAtomic(p.string(), "second\n");
  EXPECT_EQ(readAll(p), "second\n");
  EXPECT_EQ(entries(tmp.path()), 1u);
}

TEST(AtomicFile, MissingFolderIsAnErrorNamingTheFile) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "no_such_folder" / "a.txt";
  const std::string msg = errorOf([&] { writeFileAtomic(p.string(), "x", "test file"); });
  EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("No such file or directory"), std::string::npos) << msg;
}

TEST(AtomicFile, PngIsEncodedAndAnEmptyImageRefused) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "m.png";
  writePngAtomic(p.string(), cv::Mat(4, 5, CV_8UC1, cv::Scalar(255)));
  EXPECT_EQ(readAll(p).substr(1, 3), "PNG");
  EXPECT_THROW(writePngAtomic((tmp.path() / "e.png").string(), cv::Mat()), InputError);
  EXPECT_FALSE(fs::exists(tmp.path() / "e.png"));
}

TEST(AtomicFile, LibraryWriterThatFailsLeavesNothing) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "cloud.ply";
  std::string temp_seen;
  const std::string msg = errorOf([&] {
    writeThroughTempPath(
        p.string(),
        [&](const std::string& temp) {
          temp_seen = temp;
          std::ofstream(temp) << "ply\n";  // half a file, then the library reports failure
          return false;
        },
        "point cloud");
  });
  EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
  EXPECT_EQ(fs::path(temp_seen).extension(), ".ply");  // libraries choose the format by it
  EXPECT_EQ(entries(tmp.path()), 0u);
  writeThroughTempPath(p.string(),
                       [](const std::string& temp) { return static_cast<bool>(std::ofstream(temp) << "ok"); });
  EXPECT_EQ(readAll(p), "ok");
}

// A 64 KiB tmpfs over a fresh folder, unmounted at the end; skips when mounting is not allowed.
class SmallDisk {
 public:
  SmallDisk() : mounted_(::mount("tmpfs", dir_.str().c_str(), "tmpfs", 0, "size=64k") == 0) {}
  ~SmallDisk() {
    if (mounted_) ::umount(dir_.str().c_str());
  }
  bool mounted() const { return mounted_; }
  const fs::path& path() const { return dir_.path(); }

 private:
  testing::TempDir dir_;
  bool mounted_;
};

TEST(AtomicFile, FullDiskIsAnErrorAndKeepsThePreviousFile) {
  SmallDisk disk;
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here (not root); the file-size-limit test covers this";
  const fs::path p = disk.path() / "trajectory.txt";
  writeFileAtomic(p.string(), "previous\n");
  const std::string big(200 * 1024, 'x');
  const std::string msg = errorOf([&] { writeFileAtomic(p.string(), big, "trajectory file"); });
  EXPECT_NE(msg.find(p.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("No space left on device"), std::string::npos) << msg;
  EXPECT_EQ(readAll(p), "previous\n");
  EXPECT_EQ(entries(disk.path()), 1u);  // no temporary left behind
}

TEST(AtomicFile, FileSizeLimitIsAnErrorAndLeavesNoFile) {
  testing::TempDir tmp;
  const fs::path p = tmp.path() / "timings.csv";
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    // The child writes past a 4 KiB file-size limit: write() fails with EFBIG.
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{4096, 4096};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    const std::string msg = errorOf([&] { writeFileAtomic(p.string(), std::string(64 * 1024, 'x'), "timings file"); });
    const ssize_t n = ::write(fds[1], msg.data(), msg.size());
    ::_exit(n == static_cast<ssize_t>(msg.size()) ? 0 : 1);
  }
  ::close(fds[1]);
  std::string msg;
  char buf[512];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) msg.append(buf, static_cast<size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_NE(msg.find(p.string() + ": cannot write timings file: File too large"), std::string::npos) << msg;
  EXPECT_EQ(entries(tmp.path()), 0u);
}

}  // namespace
}  // namespace ff

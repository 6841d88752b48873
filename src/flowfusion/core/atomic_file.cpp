#include "flowfusion/core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"

namespace fs = std::filesystem;

namespace ff {

namespace {

// ".<stem>.tmp-<pid>-<n><extension>" beside the target: hidden, unique within and across
// processes, and with the target's extension for libraries that choose the format by it.
std::string tempPathFor(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(path);
  const std::string name = "." + p.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                           std::to_string(counter.fetch_add(1)) + p.extension().string();
  return (p.parent_path() / name).string();
}

[[noreturn]] void fail(const std::string& path, const std::string& what, int err) {
  throw InputError(path + ": cannot write " + what + ": " + std::strerror(err));
}

void renameIntoPlace(const std::string& temp, const std::string& path, const std::string& what) {
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    fail(path, what, err);
  }
}

// Lists the file in the output folder's manifest before it appears under its name, so that an
// interruption between the two leaves a listed file that does not exist, never the reverse.
void recordBeforeRename(const std::string& temp, const std::string& path) {
  try {
    detail::recordOutputFile(path);
  } catch (...) {
    ::unlink(temp.c_str());
    throw;
  }
}

}  // namespace

void writeFileAtomic(const std::string& path, std::string_view bytes, const std::string& what) {
  if (path.empty()) throw InputError("cannot write " + what + ": empty file name");
  const std::string temp = tempPathFor(path);
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) fail(path, what, errno);
  const auto abandon = [&](int err) {
    ::close(fd);
    ::unlink(temp.c_str());
    fail(path, what, err);
  };
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) abandon(n < 0 ? errno : EIO);
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    fail(path, what, err);
  }
  recordBeforeRename(temp, path);
  renameIntoPlace(temp, path, what);
}

void writePngAtomic(const std::string& path, const cv::Mat& image, const std::string& what) {
  std::vector<uchar> buf;
  bool encoded = false;
  try {
    encoded = !image.empty() && cv::imencode(".png", image, buf);
  } catch (const cv::Exception& e) {
    throw InputError(path + ": cannot encode " + what + " as PNG: " + e.what());
  }
  if (!encoded) throw InputError(path + ": cannot encode " + what + " as PNG");
  writeFileAtomic(path, std::string_view(reinterpret_cast<const char*>(buf.data()), buf.size()), what);
}

void writeThroughTempPath(const std::string& path, const std::function<bool(const std::string&)>& write,
                          const std::string& what) {
  if (path.empty()) throw InputError("cannot write " + what + ": empty file name");
  const std::string temp = tempPathFor(path);
  bool ok = false;
  try {
    ok = write(temp);
  } catch (...) {
    ::unlink(temp.c_str());
    throw;
  }
  std::error_code ec;
  const bool non_empty = ok && fs::is_regular_file(temp, ec) && fs::file_size(temp, ec) > 0 && !ec;
  if (!non_empty) {
    ::unlink(temp.c_str());
    // The library gives no reason; a (nearly) full disk is the usual one, so say what is free.
    const auto space = fs::space(fs::path(path).parent_path().empty() ? "." : fs::path(path).parent_path(), ec);
    std::string reason = "the writer failed or wrote an incomplete file";
    if (!ec) reason += " (" + std::to_string(space.available) + " bytes free on its disk)";
    throw InputError(path + ": cannot write " + what + ": " + reason);
  }
  recordBeforeRename(temp, path);
  renameIntoPlace(temp, path, what);
}

}  // namespace ff

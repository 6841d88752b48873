#include "flowfusion/core/output_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <vector>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"

namespace fs = std::filesystem;

namespace ff {

namespace {

// The folder whose writes are listed, what its manifest lists already, and its lock.
struct Recording {
  std::mutex mutex;
  std::string command;  // setOutputCommand's, "" = not named
  fs::path dir;  // weakly canonical; empty = not recording
  std::set<std::string> listed;
  bool created = false;  // prepareOutputDir made the folder
  int lock_fd = -1;      // the folder opened and flock()ed, -1 = none held
  fs::path locked_dir;   // weakly canonical
};

Recording& recording() {
  static Recording r;
  return r;
}

// `path` relative to `dir` when it lies strictly inside it (both weakly canonical), else "".
std::string relativeInside(const fs::path& dir, const fs::path& path) {
  auto d = dir.begin();
  auto p = path.begin();
  for (; d != dir.end(); ++d, ++p)
    if (p == path.end() || *d != *p) return "";
  fs::path rel;
  for (; p != path.end(); ++p) rel /= *p;
  return rel.string();
}

bool sameOrInside(const fs::path& inner, const fs::path& outer) {
  return inner == outer || !relativeInside(outer, inner).empty();
}

void appendLine(const fs::path& file, const std::string& line) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
  const std::string text = line + '\n';
  const bool ok = fd >= 0 && ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const int err = errno;
  if (fd >= 0 && ::close(fd) != 0 && ok) throw InputError(file.string() + ": cannot write: " + std::strerror(errno));
  if (!ok) throw InputError(file.string() + ": cannot write: " + std::strerror(err));
}

constexpr const char* kHeader =
    "# Files flowfusion wrote into this folder; --overwrite removes exactly these. Command: ";

// Removes the files the manifest lists (regular files inside dir only), then the folders that
// held them when they are left empty, then the manifest. Refuses another command's manifest.
void removeListedFiles(const fs::path& dir, const std::string& command) {
  const fs::path manifest = dir / kManifestName;
  std::ifstream in(manifest);
  if (!in) return;
  std::string header;
  std::getline(in, header);
  const std::string previous = header.rfind(kHeader, 0) == 0 ? header.substr(std::string(kHeader).size()) : "";
  if (!previous.empty() && !command.empty() && previous != command)
    throw InputError(dir.string() + ": holds the output of 'flowfusion " + previous +
                     "'; --overwrite replaces only the output of the same command ('" + command +
                     "'): choose another folder");
  std::set<fs::path> parents;
  std::error_code ec;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const fs::path rel = fs::path(line).lexically_normal();
    if (rel.is_absolute() || rel.empty() || *rel.begin() == "..") continue;  // not ours to touch
    const fs::path file = dir / rel;
    if (!fs::is_regular_file(fs::symlink_status(file, ec))) continue;
    if (!fs::remove(file, ec) && ec)
      throw InputError(file.string() + ": cannot remove the previous run's file: " + ec.message());
    for (fs::path p = file.parent_path(); p != dir && !relativeInside(dir, p).empty(); p = p.parent_path())
      parents.insert(p);
  }
  // Deepest first, so that a folder emptied by removing its subfolders goes too.
  for (auto it = parents.rbegin(); it != parents.rend(); ++it)
    if (fs::is_directory(*it, ec) && fs::is_empty(*it, ec)) fs::remove(*it, ec);
  fs::remove(manifest, ec);
}

// An exclusive lock on the folder itself, held while the returned descriptor is open; InputError
// when another process holds it.
int lockFolder(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw InputError(dir + ": cannot open the output folder: " + std::strerror(errno));
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return fd;
  const int err = errno;
  ::close(fd);
  if (err == EWOULDBLOCK)
    throw InputError(dir + ": another flowfusion command is writing into this output folder now; wait for it to "
                           "end or choose another folder");
  throw InputError(dir + ": cannot lock the output folder: " + std::strerror(err));
}

// Stops listing and releases the lock (the caller holds r.mutex).
void release(Recording& r) {
  if (r.lock_fd >= 0) ::close(r.lock_fd);
  r.lock_fd = -1;
  r.locked_dir.clear();
  r.dir.clear();
  r.listed.clear();
  r.created = false;
}

}  // namespace

void prepareOutputDir(const std::string& dir, bool overwrite) {
  if (dir.empty()) throw InputError("the output folder name is empty");
  Recording& r = recording();
  const fs::path p(dir);
  std::error_code ec;
  const bool existed = fs::exists(p, ec);
  if (existed && !fs::is_directory(p, ec)) throw InputError(dir + ": output path exists and is not a folder");
  fs::create_directories(p, ec);
  if (ec) throw InputError(dir + ": cannot create output folder: " + ec.message());
  const fs::path canonical = fs::weakly_canonical(p);
  std::string command;
  int held = -1;
  {
    const std::lock_guard<std::mutex> lock(r.mutex);
    command = r.command;
    if (r.locked_dir == canonical) held = r.lock_fd;  // this process holds it already
  }
  const int fd = held >= 0 ? held : lockFolder(dir);
  try {
    if (existed && !fs::is_empty(p, ec)) {
      if (!overwrite) throw InputError(dir + ": output folder is not empty; choose another or pass --overwrite");
      removeListedFiles(p, command);
    }
    writeFileAtomic((p / kManifestName).string(), kHeader + command + "\n", "manifest");
  } catch (...) {
    if (fd != held) ::close(fd);
    throw;
  }
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (fd != held) {
    release(r);
    r.lock_fd = fd;
    r.locked_dir = canonical;
  }
  r.dir = canonical;
  r.listed.clear();
  r.created = !existed;
}

void releaseOutputDir() {
  Recording& r = recording();
  const std::lock_guard<std::mutex> lock(r.mutex);
  release(r);
}

void abandonOutputDir() {
  Recording& r = recording();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.dir.empty()) return;
  std::error_code ec;
  try {
    removeListedFiles(r.dir, r.command);
    if (r.created && fs::is_empty(r.dir, ec)) fs::remove(r.dir, ec);
  } catch (const InputError&) {
    // Nothing more to undo: the failure that led here is the one to report.
  }
  release(r);
}

void setOutputCommand(const std::string& command) {
  Recording& r = recording();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.command = command;
}

void refuseOverlap(const std::string& out_dir, const std::string& input, const std::string& what) {
  const fs::path out = fs::weakly_canonical(out_dir), in = fs::weakly_canonical(input);
  std::string relation;
  if (out == in) relation = " is ";
  else if (sameOrInside(in, out)) relation = " contains ";
  else if (sameOrInside(out, in)) relation = " lies inside ";
  else return;
  throw InputError(out_dir + relation + what + " (" + input +
                   "); results never go into an input, even with --overwrite: choose another output folder");
}

namespace detail {

void recordOutputFile(const std::string& path) {
  Recording& r = recording();
  const std::lock_guard<std::mutex> lock(r.mutex);
  if (r.dir.empty()) return;
  const std::string rel = relativeInside(r.dir, fs::weakly_canonical(path));
  if (rel.empty() || rel == kManifestName || !r.listed.insert(rel).second) return;
  appendLine(r.dir / kManifestName, rel);
}

}  // namespace detail

}  // namespace ff

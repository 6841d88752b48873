#include "flowfusion/slam/map_file.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/file_bytes.h"
#include "flowfusion/core/output_folder.h"

namespace ff {

namespace {

static_assert(std::endian::native == std::endian::little, "map.ffmap is little-endian, as this host must be");

constexpr char kMagic[8] = {'F', 'F', 'M', 'A', 'P', '\r', '\n', '\x1a'};  // PNG-style: text-mode damage shows
constexpr size_t kFloatsPerSurfel = 12;  // position 3, normal 3, radius, confidence, bgr 3, intensity
constexpr size_t kPoseDoubles = 12;      // rotation row-major, translation

// FNV-1a, 64 bit: enough to tell a damaged file from a whole one.
uint64_t checksum(const char* data, size_t size) {
  uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < size; ++i) h = (h ^ static_cast<uint8_t>(data[i])) * 0x100000001b3ULL;
  return h;
}

template <class T>
void put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// An image: its OpenCV type, rows, cols, byte count and bytes (PNG for 8- and 16-bit, raw floats).
void putImage(std::string& out, const cv::Mat& image) {
  std::vector<uint8_t> bytes;
  if (image.depth() == CV_32F) {
    const cv::Mat c = image.isContinuous() ? image : image.clone();
    bytes.assign(c.data, c.data + c.total() * c.elemSize());
  } else if (!cv::imencode(".png", image, bytes)) {
    throw InputError("map file: PNG encoding of a keyframe image failed");
  }
  put(out, static_cast<uint32_t>(image.type()));
  put(out, static_cast<uint32_t>(image.rows));
  put(out, static_cast<uint32_t>(image.cols));
  put(out, static_cast<uint32_t>(bytes.size()));
  out.append(reinterpret_cast<const char*>(bytes.data()), bytes.size());
}

nlohmann::json headerOf(const SavedMap& map) {
  const CameraIntrinsics& c = map.camera;
  return {{"camera", {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"width", c.width}, {"height", c.height}}},
          {"keyframe_level", map.keyframe_level},
          {"fern_image_width", map.fern_image_width},
          {"surfels", map.surfels.size()},
          {"keyframes", map.keyframes.size()}};
}

// Reads the file's parts in order; every read past the end is the file's truncation.
class Reader {
 public:
  Reader(const std::string& path, const std::string& bytes, size_t end) : path_(path), bytes_(bytes), end_(end) {}

  [[noreturn]] void fail(const std::string& reason) const { throw InputError(path_ + ": " + reason); }
  const char* take(size_t n) {
    if (n > end_ - pos_) fail("truncated map file (ends inside its data)");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  template <class T>
  T get() {
    T value;
    std::memcpy(&value, take(sizeof(T)), sizeof(T));
    return value;
  }
  cv::Mat image(int type, cv::Size size, const char* what);
  bool atEnd() const { return pos_ == end_; }

 private:
  const std::string& path_;
  const std::string& bytes_;
  size_t end_;
  size_t pos_ = 0;
};

cv::Mat Reader::image(int type, cv::Size size, const char* what) {
  const auto stored_type = get<uint32_t>();
  const auto rows = get<uint32_t>(), cols = get<uint32_t>(), count = get<uint32_t>();
  if (static_cast<int>(stored_type) != type || static_cast<int>(rows) != size.height ||
      static_cast<int>(cols) != size.width)
    fail(std::string("corrupt map file: a keyframe's ") + what + " image is not " + std::to_string(size.width) + "x" +
         std::to_string(size.height) + " of the expected type");
  const char* data = take(count);
  cv::Mat out;
  if (CV_MAT_DEPTH(type) == CV_32F) {
    if (count != rows * cols * CV_ELEM_SIZE(type)) fail(std::string("corrupt map file: a keyframe's ") + what + " image");
    out = cv::Mat(size, type);
    std::memcpy(out.data, data, count);
  } else {
    out = cv::imdecode(cv::Mat(1, static_cast<int>(count), CV_8U, const_cast<char*>(data)), cv::IMREAD_UNCHANGED);
    if (out.type() != type || out.size() != size) fail(std::string("corrupt map file: a keyframe's ") + what + " image");
  }
  return out;
}

CameraIntrinsics cameraOf(const nlohmann::json& j) {
  CameraIntrinsics c;
  c.fx = j.at("fx").get<double>();
  c.fy = j.at("fy").get<double>();
  c.cx = j.at("cx").get<double>();
  c.cy = j.at("cy").get<double>();
  c.width = j.at("width").get<int>();
  c.height = j.at("height").get<int>();
  return c;
}

// The header's figures, checked as far as they can be alone.
void readHeader(Reader& in, SavedMap& map, size_t& surfels, size_t& keyframes) {
  const auto length = in.get<uint32_t>();
  const char* text = in.take(length);
  try {
    const nlohmann::json j = nlohmann::json::parse(text, text + length);
    map.camera = cameraOf(j.at("camera"));
    map.keyframe_level = j.at("keyframe_level").get<int>();
    map.fern_image_width = j.at("fern_image_width").get<int>();
    surfels = j.at("surfels").get<size_t>();
    keyframes = j.at("keyframes").get<size_t>();
  } catch (const nlohmann::json::exception& e) {
    in.fail(std::string("corrupt map file header: ") + e.what());
  }
  if (!map.camera.valid() || map.keyframe_level < 0 || map.keyframe_level > 8 || map.fern_image_width < 1 ||
      map.fern_image_width > 4096)
    in.fail("corrupt map file header: camera or keyframe image sizes out of range");
}

void readSurfels(Reader& in, std::vector<Surfel>& surfels, size_t count) {
  if (count > (1u << 30)) in.fail("corrupt map file header: " + std::to_string(count) + " surfels");
  surfels.resize(count);
  for (Surfel& s : surfels) {
    float f[kFloatsPerSurfel];
    std::memcpy(f, in.take(sizeof f), sizeof f);
    s.position = Eigen::Vector3f(f[0], f[1], f[2]);
    s.normal = Eigen::Vector3f(f[3], f[4], f[5]);
    s.radius = f[6];
    s.confidence = f[7];
    std::copy(f + 8, f + 11, s.bgr);
    s.intensity = f[11];
    if (!std::isfinite(f[0] + f[1] + f[2] + f[3] + f[4] + f[5] + f[6] + f[7]))
      in.fail("corrupt map file: a surfel holds a non-finite value");
  }
}

SavedKeyframe readKeyframe(Reader& in, const SavedMap& map) {
  SavedKeyframe k;
  double p[kPoseDoubles];
  std::memcpy(p, in.take(sizeof p), sizeof p);
  k.T_world_kf = SE3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) k.T_world_kf.linear()(r, c) = p[3 * r + c];
    k.T_world_kf.translation()(r) = p[9 + r];
  }
  const Eigen::Matrix3d R = k.T_world_kf.linear();
  if (!R.allFinite() || !k.T_world_kf.translation().allFinite() ||
      (R * R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6)
    in.fail("corrupt map file: a keyframe pose is not a rigid motion");
  auto images = std::make_shared<KeyframeImages>();
  images->camera = map.camera.atLevel(map.keyframe_level);
  const cv::Size size(images->camera.width, images->camera.height);
  const cv::Size small(map.fern_image_width, std::max(1, map.fern_image_width * map.camera.height / map.camera.width));
  images->intensity = in.image(CV_8U, size, "intensity");
  images->depth = in.image(CV_16U, size, "depth");
  images->static_weight = in.image(CV_8U, size, "static weight");
  images->small_bgr = in.image(CV_8UC3, small, "small colour");
  images->small_depth = in.image(CV_32F, small, "small depth");
  k.images = std::move(images);
  return k;
}

std::string readAll(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no map file there (--map-in)");
  std::optional<std::string> bytes = readFileBytes(path);
  if (!bytes) throw InputError(path + ": cannot read the map file");
  return std::move(*bytes);
}

}  // namespace

SavedMap savedMap(const StaticMap* map, std::vector<SavedKeyframe> keyframes, const CameraIntrinsics& camera,
                  const SlamConfig& slam) {
  SavedMap out;
  out.camera = camera;
  out.keyframe_level = slam.keyframe_level;
  out.fern_image_width = slam.fern_image_width;
  out.keyframes = std::move(keyframes);
  if (map)
    for (const Surfel& s : map->surfels())
      if (s.confidence >= map->config().stable_confidence) out.surfels.push_back(s);
  return out;
}

void writeMapFile(const std::string& path, const SavedMap& map) {
  std::string out(kMagic, sizeof kMagic);
  put(out, kMapFileVersion);
  const std::string header = headerOf(map).dump();
  put(out, static_cast<uint32_t>(header.size()));
  out += header;
  for (const Surfel& s : map.surfels) {
    const float f[kFloatsPerSurfel] = {s.position.x(), s.position.y(), s.position.z(), s.normal.x(), s.normal.y(),
                                       s.normal.z(),   s.radius,       s.confidence,   s.bgr[0],     s.bgr[1],
                                       s.bgr[2],       s.intensity};
    out.append(reinterpret_cast<const char*>(f), sizeof f);
  }
  for (const SavedKeyframe& k : map.keyframes) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) put(out, k.T_world_kf.linear()(r, c));
    for (int r = 0; r < 3; ++r) put(out, k.T_world_kf.translation()(r));
    for (const cv::Mat* image : {&k.images->intensity, &k.images->depth, &k.images->static_weight,
                                 &k.images->small_bgr, &k.images->small_depth})
      putImage(out, *image);
  }
  put(out, checksum(out.data(), out.size()));
  writeFileAtomic(path, out, "map file");
}

SavedMap readMapFile(const std::string& path) {
  const std::string bytes = readAll(path);
  if (bytes.size() < sizeof kMagic + sizeof(uint32_t) || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw InputError(path + ": not a flowfusion map file (no FFMAP header)");
  uint32_t version = 0;
  std::memcpy(&version, bytes.data() + sizeof kMagic, sizeof version);
  if (version != kMapFileVersion)
    throw InputError(path + ": map file version " + std::to_string(version) + ", this build reads version " +
                     std::to_string(kMapFileVersion));
  if (bytes.size() < sizeof kMagic + sizeof version + sizeof(uint64_t))
    throw InputError(path + ": truncated map file");
  const size_t end = bytes.size() - sizeof(uint64_t);
  uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + end, sizeof stored);
  if (stored != checksum(bytes.data(), end))
    throw InputError(path + ": corrupt or truncated map file (checksum mismatch)");
  Reader in(path, bytes, end);
  in.take(sizeof kMagic + sizeof version);
  SavedMap map;
  map.path = path;
  size_t surfels = 0, keyframes = 0;
  readHeader(in, map, surfels, keyframes);
  readSurfels(in, map.surfels, surfels);
  for (size_t i = 0; i < keyframes; ++i) map.keyframes.push_back(readKeyframe(in, map));
  if (!in.atEnd()) in.fail("corrupt map file: data after its last keyframe");
  return map;
}

std::string mapFileIn(const std::string& path) {
  return std::filesystem::is_directory(path) ? (std::filesystem::path(path) / kMapFileName).string() : path;
}

void checkMapFits(const SavedMap& map, const CameraIntrinsics& camera, const SlamConfig& slam) {
  const CameraIntrinsics& m = map.camera;
  const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(1.0, std::abs(b)); };
  if (m.width != camera.width || m.height != camera.height || !near(m.fx, camera.fx) || !near(m.fy, camera.fy) ||
      !near(m.cx, camera.cx) || !near(m.cy, camera.cy)) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "the map is of another camera: %dx%d fx %.3f fy %.3f cx %.3f cy %.3f, this sequence's is %dx%d fx "
                  "%.3f fy %.3f cx %.3f cy %.3f",
                  m.width, m.height, m.fx, m.fy, m.cx, m.cy, camera.width, camera.height, camera.fx, camera.fy,
                  camera.cx, camera.cy);
    throw InputError(map.path + ": " + text);
  }
  if (map.keyframe_level != slam.keyframe_level)
    throw InputError(map.path + ": the map's keyframes are at slam.keyframe_level " +
                     std::to_string(map.keyframe_level) + ", this run's is " + std::to_string(slam.keyframe_level));
  if (map.fern_image_width != slam.fern_image_width)
    throw InputError(map.path + ": the map's keyframes have slam.fern_image_width " +
                     std::to_string(map.fern_image_width) + ", this run's is " + std::to_string(slam.fern_image_width));
  if (map.keyframes.empty())
    throw InputError(map.path + ": the map holds no keyframes to localize against (its run had loop closure off)");
}

SavedMap readMapFor(const std::string& map_in, const std::string& out_dir, const CameraIntrinsics& camera,
                    const SlamConfig& slam) {
  const std::string path = mapFileIn(map_in);
  if (!out_dir.empty()) {
    refuseOverlap(out_dir, map_in, "the --map-in map");
    refuseOverlap(out_dir, path, "the --map-in map");
  }
  SavedMap map = readMapFile(path);
  checkMapFits(map, camera, slam);
  if (slam.loop_closure == LoopClosureMode::Off || !loopClosureAvailable())
    throw InputError(path + ": continuing in a saved map needs loop closure (slam.loop_closure ferns, in a build "
                     "with Ceres)");
  return map;
}

}  // namespace ff

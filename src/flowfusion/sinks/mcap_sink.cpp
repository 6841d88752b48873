#include "flowfusion/sinks/mcap_sink.h"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

#include "flowfusion/fusion/static_map.h"
#include "flowfusion/io/mcap_writer.h"
#include "flowfusion/pipeline/flowfusion_system.h"

namespace ff {

namespace {

using nlohmann::json;

// JSON Schemas of the foxglove messages written, each declaring the fields this sink fills.
json object(json properties) { return {{"type", "object"}, {"properties", std::move(properties)}}; }
json number() { return {{"type", "number"}}; }
json integer() { return {{"type", "integer"}}; }
json text() { return {{"type", "string"}}; }
json bytes() { return {{"type", "string"}, {"contentEncoding", "base64"}}; }
json numbers() { return {{"type", "array"}, {"items", number()}}; }
json timeSchema() { return object({{"sec", integer()}, {"nsec", integer()}}); }
json vector3() { return object({{"x", number()}, {"y", number()}, {"z", number()}}); }
json quaternion() { return object({{"x", number()}, {"y", number()}, {"z", number()}, {"w", number()}}); }
json poseSchema() { return object({{"position", vector3()}, {"orientation", quaternion()}}); }

json schemaOf(const std::string& name) {
  json s;
  if (name == "foxglove.PoseInFrame") s = object({{"timestamp", timeSchema()}, {"frame_id", text()}, {"pose", poseSchema()}});
  if (name == "foxglove.PosesInFrame")
    s = object({{"timestamp", timeSchema()}, {"frame_id", text()}, {"poses", {{"type", "array"}, {"items", poseSchema()}}}});
  if (name == "foxglove.FrameTransform")
    s = object({{"timestamp", timeSchema()}, {"parent_frame_id", text()}, {"child_frame_id", text()},
                {"translation", vector3()}, {"rotation", quaternion()}});
  if (name == "foxglove.RawImage")
    s = object({{"timestamp", timeSchema()}, {"frame_id", text()}, {"width", integer()}, {"height", integer()},
                {"encoding", text()}, {"step", integer()}, {"data", bytes()}});
  if (name == "foxglove.CameraCalibration")
    s = object({{"timestamp", timeSchema()}, {"frame_id", text()}, {"width", integer()}, {"height", integer()},
                {"distortion_model", text()}, {"D", numbers()}, {"K", numbers()}, {"R", numbers()}, {"P", numbers()}});
  if (name == "foxglove.PointCloud")
    s = object({{"timestamp", timeSchema()}, {"frame_id", text()}, {"pose", poseSchema()}, {"point_stride", integer()},
                {"fields", {{"type", "array"},
                            {"items", object({{"name", text()}, {"offset", integer()}, {"type", integer()}})}}},
                {"data", bytes()}});
  s["title"] = name;
  s["$schema"] = "https://json-schema.org/draft/2020-12/schema";
  return s;
}

std::string base64(const uint8_t* p, size_t n) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (size_t i = 0; i < n; i += 3) {
    const uint32_t v = uint32_t(p[i]) << 16 | (i + 1 < n ? uint32_t(p[i + 1]) << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
    out += k[v >> 18 & 63];
    out += k[v >> 12 & 63];
    out += i + 1 < n ? k[v >> 6 & 63] : '=';
    out += i + 2 < n ? k[v & 63] : '=';
  }
  return out;
}

// Whole seconds and nanoseconds of a stamp in seconds.
json stamp(double t) {
  const auto ns = static_cast<int64_t>(std::llround(t * 1e9));
  return {{"sec", ns / 1000000000}, {"nsec", ns % 1000000000}};
}
uint64_t nanos(double t) { return static_cast<uint64_t>(std::llround(t * 1e9)); }

json pose(const SE3& T) {
  const Eigen::Quaterniond q(T.rotation());
  const Eigen::Vector3d t = T.translation();
  return {{"position", {{"x", t.x()}, {"y", t.y()}, {"z", t.z()}}},
          {"orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}

json rawImage(double t, const cv::Mat& image, const std::string& encoding) {
  const cv::Mat m = image.isContinuous() ? image : image.clone();
  const size_t step = m.cols * m.elemSize();
  return {{"timestamp", stamp(t)}, {"frame_id", "camera"}, {"width", m.cols}, {"height", m.rows},
          {"encoding", encoding}, {"step", step}, {"data", base64(m.data, step * m.rows)}};
}

}  // namespace

struct McapSink::Channels {
  uint16_t pose, tf, path, color, mask, depth, calibration, map;
};

McapSink::McapSink(const std::string& path) : writer_(std::make_unique<McapFileWriter>(path)) {
  const auto channel = [&](const std::string& topic, const std::string& schema) {
    return writer_->addChannel(topic, writer_->addSchema(schema, "jsonschema", schemaOf(schema).dump()), "json");
  };
  channels_ = std::make_unique<Channels>();
  channels_->pose = channel("/camera/pose", "foxglove.PoseInFrame");
  channels_->tf = channel("/tf", "foxglove.FrameTransform");
  channels_->path = channel("/camera/path", "foxglove.PosesInFrame");
  const uint16_t raw_image = writer_->addSchema("foxglove.RawImage", "jsonschema", schemaOf("foxglove.RawImage").dump());
  channels_->color = writer_->addChannel("/camera/color", raw_image, "json");
  channels_->mask = writer_->addChannel("/camera/mask", raw_image, "json");
  channels_->depth = writer_->addChannel("/camera/depth", raw_image, "json");
  channels_->calibration = channel("/camera/calibration", "foxglove.CameraCalibration");
  channels_->map = channel("/map", "foxglove.PointCloud");
}

McapSink::~McapSink() = default;

void McapSink::begin(const RunInfo& info) { camera_ = info.camera; }

void McapSink::frame(const RgbdFrame& frame, const FrameResult& result) {
  const double t = result.timestamp;
  const Channels& c = *channels_;
  if (!calibration_written_) {
    const CameraIntrinsics& k = camera_;
    writer_->write(c.calibration, nanos(t),
                   json{{"timestamp", stamp(t)}, {"frame_id", "camera"}, {"width", k.width}, {"height", k.height},
                        {"distortion_model", "plumb_bob"}, {"D", {0, 0, 0, 0, 0}},
                        {"K", {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1}}, {"R", {1, 0, 0, 0, 1, 0, 0, 0, 1}},
                        {"P", {k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0}}}
                       .dump());
    calibration_written_ = true;
  }
  if (result.has_pose) {
    const json p = pose(result.T_world_cam);
    writer_->write(c.pose, nanos(t), json{{"timestamp", stamp(t)}, {"frame_id", "world"}, {"pose", p}}.dump());
    writer_->write(c.tf, nanos(t),
                   json{{"timestamp", stamp(t)}, {"parent_frame_id", "world"}, {"child_frame_id", "camera"},
                        {"translation", p["position"]}, {"rotation", p["orientation"]}}
                       .dump());
  }
  writer_->write(c.color, nanos(t), rawImage(t, frame.color, "bgr8").dump());
  if (!result.dynamic_mask.empty()) writer_->write(c.mask, nanos(t), rawImage(t, result.dynamic_mask, "mono8").dump());
  writer_->write(c.depth, nanos(t), rawImage(t, frame.depth, "32FC1").dump());
}

void McapSink::end(RunSummary& summary, const StaticMap* map) {
  std::vector<McapMapPoint> points;
  if (map)
    for (const Surfel& s : map->surfels()) {
      if (s.confidence < map->config().stable_confidence) continue;
      McapMapPoint p;
      p.position = s.position;
      for (int k = 0; k < 3; ++k) p.rgb[k] = uint8_t(std::lround(s.bgr[2 - k]));
      points.push_back(p);
    }
  finish(summary.trajectory, points);
  summary.written.push_back(writer_->path());
}

void McapSink::finish(const Trajectory& trajectory, const std::vector<McapMapPoint>& map) {
  const double t = trajectory.empty() ? 0.0 : trajectory.back().timestamp;
  json poses = json::array();
  for (const StampedPose& s : trajectory) poses.push_back(pose(s.T_world_cam));
  writer_->write(channels_->path, nanos(t), json{{"timestamp", stamp(t)}, {"frame_id", "world"}, {"poses", poses}}.dump());
  std::vector<uint8_t> data(map.size() * 16);
  for (size_t i = 0; i < map.size(); ++i) {
    std::memcpy(&data[i * 16], map[i].position.data(), 12);
    std::memcpy(&data[i * 16 + 12], map[i].rgb, 3);
    data[i * 16 + 15] = 255;
  }
  const json fields = json::array({{{"name", "x"}, {"offset", 0}, {"type", 7}}, {{"name", "y"}, {"offset", 4}, {"type", 7}},
                                   {{"name", "z"}, {"offset", 8}, {"type", 7}}, {{"name", "red"}, {"offset", 12}, {"type", 1}},
                                   {{"name", "green"}, {"offset", 13}, {"type", 1}},
                                   {{"name", "blue"}, {"offset", 14}, {"type", 1}},
                                   {{"name", "alpha"}, {"offset", 15}, {"type", 1}}});  // 7 FLOAT32, 1 UINT8
  writer_->write(channels_->map, nanos(t),
                 json{{"timestamp", stamp(t)}, {"frame_id", "world"}, {"pose", pose(SE3::Identity())},
                      {"point_stride", 16}, {"fields", fields}, {"data", base64(data.data(), data.size())}}
                     .dump());
  writer_->close();
}

}  // namespace ff

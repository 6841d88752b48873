// `flowfusion synth` and `flowfusion augment`: synthetic dynamic RGB-D sequences with exact
// ground truth (TUM layout with masks/, groundtruth.txt, camera.txt, scene.json).
#include <chrono>
#include <iostream>
#include <map>
#include <memory>

#include "command.h"
#include "config_sources.h"
#include "flowfusion/core/error.h"
#include "flowfusion/core/output_folder.h"
#include "flowfusion/io/frame_source.h"
#include "flowfusion/io/tum_text.h"
#include "flowfusion/synth/synthetic_scene.h"

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The longest sequence synth writes, about 55 minutes at 30 Hz: a larger count is a typo that
// would fill the disk.
constexpr int kMaxSynthFrames = 100000;

// Bounds the library's validation leaves open: the frame count, and timestamps that stay below
// what the sequence readers accept.
void checkSynthRange(const ff::synth::SynthConfig& config) {
  ff::synth::SynthConfig c = config;
  c.frames = ff::synth::frameCount(config);
  if (c.frames > kMaxSynthFrames)
    throw ff::InputError("--frames: at most " + std::to_string(kMaxSynthFrames) +
                         " frames (about 55 minutes at 30 Hz), got " + std::to_string(c.frames));
  const double last_s = c.start_time + (c.frames - 1) / c.fps;
  if (!(last_s < ff::kMaxTimestampS))
    throw ff::InputError("synth: the last timestamp (start_time + frames / fps) must stay below 1e10 s");
}

// CLI11 reads "-1" into an unsigned seed as 2^64 - 1: a sign is refused before that.
void refuseNegativeSeed(const std::string& value) {
  if (value.find('-') != std::string::npos) throw ff::InputError("--seed: must be 0 or more, got " + value);
}

const ff::app::RegisterCommand synth_command("50-synth", [](CLI::App& app) {
  struct Options {
    std::string out;
    ff::app::ConfigSources sources;
    ff::synth::SynthConfig config;
    bool no_noise = false, overwrite = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "synth", "Render a synthetic dynamic indoor RGB-D sequence with exact ground truth (TUM layout + masks)");
  cmd->add_option("OUT", o->out, "Output folder")->required();
  cmd->add_option("--seed", o->config.seed, "Random seed (room, camera path, objects, noise)")
      ->capture_default_str()
      ->each(refuseNegativeSeed);
  cmd->add_option("--frames", o->config.frames, "Number of frames")->capture_default_str();
  cmd->add_option("--objects", o->config.objects, "Moving objects (0: the static twin of the same seed)")
      ->capture_default_str();
  cmd->add_option("--width", o->config.width, "Image width, pixels")->capture_default_str();
  cmd->add_option("--height", o->config.height, "Image height, pixels")->capture_default_str();
  cmd->add_option("--fps", o->config.fps, "Frame rate, Hz")->capture_default_str();
  cmd->add_option("--camera-speed", o->config.camera_speed, "RMS camera speed, m/s")->capture_default_str();
  cmd->add_option("--angular-speed", o->config.camera_angular_speed, "RMS camera angular speed, deg/s")
      ->capture_default_str();
  cmd->add_option("--object-speed", o->config.object_speed, "RMS object speed, m/s")->capture_default_str();
  cmd->add_flag("--no-noise", o->no_noise, "Exact depth without holes, noise-free colour");
  cmd->add_option("--people", o->config.people, "Articulated people walking across the first view (0..8)")
      ->capture_default_str();
  cmd->add_option("--seats", o->config.seats,
                  "Seats in the first view (static); person k < seats sits on seat k (0..4)")
      ->capture_default_str();
  cmd->add_option("--near-objects", o->config.near_objects,
                  "Large boxes 1.0-1.5 m in front of the first camera, crossing its view (0..4)")
      ->capture_default_str();
  cmd->add_option("--pushed-objects", o->config.pushed_objects,
                  "Chairs and boxes that rest, are pushed, rest, are pushed back (0..4)")
      ->capture_default_str();
  cmd->add_option("--rest-s", o->config.rest_s, "Seconds pushed objects rest before each push")->capture_default_str();
  cmd->add_option("--camera-motion", o->config.camera_motion,
                  "handheld (mostly yaw) or rpy (fast rotation about all axes; speed from --angular-speed)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, ff::synth::CameraMotion>{
                                              {"handheld", ff::synth::CameraMotion::Handheld},
                                              {"rpy", ff::synth::CameraMotion::Rpy}},
                                          CLI::ignore_case));
  cmd->add_option("--camera-path", o->config.camera_path,
                  "sweep (hand-held about the room's centre) or loop (round a 0.6 m circle looking outwards, "
                  "at --camera-speed; for loop closure)")
      ->transform(CLI::CheckedTransformer(std::map<std::string, ff::synth::CameraPathKind>{
                                              {"sweep", ff::synth::CameraPathKind::Sweep},
                                              {"loop", ff::synth::CameraPathKind::Loop}},
                                          CLI::ignore_case));
  cmd->add_option("--laps", o->config.laps, "With --camera-path loop: this many laps (sets --frames; 0: --frames)")
      ->capture_default_str();
  cmd->add_option("--path-start", o->config.path_start_s,
                  "A second recording of the same room (map reuse): the camera path starts this many s along; "
                  "the ground truth stays in the room's world frame")
      ->capture_default_str();
  cmd->add_option("--path-seed", o->config.path_seed,
                  "With --camera-path loop: the loop's hand-held wobble from this seed (0: --seed), the room unchanged")
      ->capture_default_str();
  cmd->add_option("--cover-at", o->config.cover_at_s, "Kidnap: the view covered (black, no depth) from this s after the start")
      ->capture_default_str();
  cmd->add_option("--cover-s", o->config.cover_s, "Kidnap: for this many seconds (0: never), the camera moving on")
      ->capture_default_str();
  cmd->add_option("--exposure-ms", o->config.exposure_ms,
                  "Motion blur: exposure time in ms over which camera and objects move (0: off)")
      ->capture_default_str();
  cmd->add_option("--exposure-samples", o->config.exposure_samples, "Sub-frame renders averaged per exposure")
      ->capture_default_str();
  o->sources.addTo(cmd, "SynthConfig");
  cmd->add_flag("--overwrite", o->overwrite, "Write into a non-empty output folder");
  cmd->callback([o] {
    ff::synth::SynthConfig defaults = o->config;
    if (o->no_noise) defaults.noise = false;
    const auto config = o->sources.resolve(defaults);
    checkSynthRange(config);
    ff::setOutputCommand("synth");
    const auto t0 = std::chrono::steady_clock::now();
    const ff::synth::SyntheticScene scene(config);
    ff::synth::writeSequence(scene, o->out, o->overwrite);
    std::cout << "synth: wrote " << scene.frameCount() << " frames (" << scene.camera().width << "x"
              << scene.camera().height << ", " << scene.objectCount() << " moving objects of which "
              << scene.personCount() << " people, seed " << config.seed
              << ") to " << o->out << " in " << secondsSince(t0) << " s\n";
  });
});

const ff::app::RegisterCommand augment_command("51-augment", [](CLI::App& app) {
  struct Options {
    std::string input, out, frames;
    ff::app::ConfigSources sources;
    ff::synth::AugmentConfig config;
    ff::SequenceOptions sequence;
    bool no_noise = false, no_undistort = false, overwrite = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "augment", "Insert textured moving objects into a real static sequence with ground truth (TUM layout)");
  cmd->add_option("STATIC_SEQUENCE", o->input, "Static TUM sequence folder with groundtruth.txt")->required();
  cmd->add_option("OUT", o->out, "Output folder")->required();
  cmd->add_option("--seed", o->config.seed, "Random seed (objects, paths, noise)")
      ->capture_default_str()
      ->each(refuseNegativeSeed);
  cmd->add_option("--objects", o->config.objects, "Number of inserted objects")->capture_default_str();
  cmd->add_option("--camera", o->sequence.camera,
                  "Intrinsics: fr1|fr2|fr3 or fx,fy,cx,cy[,width,height[,k1,k2,p1,p2,k3]] (default: detect); the "
                  "output is undistorted and its camera.txt pinhole");
  cmd->add_option("--frames", o->frames, "Colour frame range FIRST:LAST (inclusive indices)");
  cmd->add_option("--object-speed", o->config.object_speed, "RMS object speed, m/s")->capture_default_str();
  cmd->add_option("--people", o->config.people,
                  "Articulated people walking across the first view, 1.0-1.6 m in front (0..8)")
      ->capture_default_str();
  cmd->add_option("--camera-height", o->config.camera_height,
                  "Height of the first camera above the floor the people walk on, m")
      ->capture_default_str();
  cmd->add_flag("--no-noise", o->no_noise, "No depth noise on the inserted objects");
  cmd->add_flag("--no-undistort", o->no_undistort, "Keep the raw images (ignore the camera's lens distortion)");
  o->sources.addTo(cmd, "AugmentConfig");
  cmd->add_flag("--overwrite", o->overwrite, "Write into a non-empty output folder");
  cmd->callback([o] {
    ff::synth::AugmentConfig defaults = o->config;
    if (o->no_noise) defaults.noise = false;
    if (!o->frames.empty()) {
      const ff::FrameRange range = ff::parseFrameRange(o->frames);
      defaults.first_frame = range.first;
      defaults.last_frame = range.last;
    }
    const auto config = o->sources.resolve(defaults);
    o->sequence.undistort = !o->no_undistort;
    const auto t0 = std::chrono::steady_clock::now();
    ff::refuseOverlap(o->out, o->input, "the input sequence");
    ff::setOutputCommand("augment");
    const auto report = ff::synth::augmentSequence(o->input, o->out, config, o->sequence, o->overwrite);
    if (!report.dropped_timestamps.empty()) {
      std::cerr << "augment: dropped " << report.dropped_timestamps.size()
                << " colour frame(s) without a ground-truth pose:";
      for (double t : report.dropped_timestamps) std::cerr << ' ' << ff::timestampName(t);
      std::cerr << '\n';
    }
    std::cout << "augment: wrote " << report.frames_written << " frames with " << config.objects
              << " moving objects and " << config.people << " people to " << o->out << " in " << secondsSince(t0)
              << " s\n";
  });
});

}  // namespace

#include "flowfusion/slam/loop_closer.h"

#include <algorithm>
#include <deque>
#include <future>
#include <spdlog/spdlog.h>

#include "flowfusion/core/error.h"
#include "flowfusion/slam/keyframe.h"
#include "flowfusion/slam/loop_verifier.h"
#include "flowfusion/slam/place_index.h"
#include "flowfusion/slam/pose_graph.h"

namespace ff {

namespace {

constexpr double kDeg = M_PI / 180.0;

// What one keyframe's check found: the corrected poses of keyframes 0..K when it closed a loop.
struct CheckResult {
  int loops = 0;
  std::vector<SE3> poses;
};

// Randomized ferns propose, the dense odometry verifies, a Ceres pose graph corrects.
class FernLoopCloser final : public SlamBackEnd {
 public:
  FernLoopCloser(const SlamConfig& config, const OdometryConfig& odometry, const CameraIntrinsics& camera)
      : config_(config),
        odometry_(odometry),
        camera_(camera),
        index_(config.fern_count,
               cv::Size(config.fern_image_width, std::max(1, config.fern_image_width * camera.height / camera.width)),
               odometry.min_depth, std::min(odometry.max_depth, 5.0)) {}
  ~FernLoopCloser() override { finish(); }

  void frameTracked(const TrackedFrameInfo& info) override;
  std::optional<MapCorrection> takeCorrection() override;
  std::optional<SE3> relocalize(const RgbdFrame& frame, const cv::Mat& scores) override;
  void finish() override {
    for (Pending& p : pending_) {
      p.due_frame = frame_index_;
      p.result.wait();
    }
    finishing_ = true;
  }
  Trajectory trajectory() const override;
  void loadKeyframes(const std::vector<SavedKeyframe>& keyframes) override;
  std::vector<SavedKeyframe> savedKeyframes() const override;
  int loopClosures() const override { return closures_; }
  int corrections() const override { return corrections_; }
  int keyframes() const override;

 private:
  struct FrameRef {
    double timestamp;
    int keyframe;   // -1: before the first keyframe
    SE3 T_kf_cam;   // the reported pose relative to it (or the pose itself)
    SE3 T_world_cam;  // the reported pose (a lost frame's: bridged once tracked again), until a loop closes
    // Once the next keyframe is made: the pose relative to it, and how far along the frames from
    // one keyframe to the next this one lies (0: the keyframe before alone places it).
    SE3 T_next_cam = SE3::Identity();
    double along = 0;
  };
  struct Pending {
    int due_frame;
    std::shared_future<CheckResult> result;
  };

  // Whether two poses lie within slam.keyframe_translation_m and _rotation_deg of each other: a new
  // keyframe is made beyond that, and a loop found within it covers the keyframe's view.
  bool withinKeyframeSpacing(const SE3& T_a_b) const;
  // Waits for the checks still running: they add to the place index and the keyframe images.
  void waitForChecks() const;
  bool needsKeyframe(const SE3& T_world_cam) const;
  void addKeyframe(const TrackedFrameInfo& info);
  // The frames since the latest keyframe, relative to the one made now at T_world_kf as well.
  void closeSpan(const SE3& T_world_kf);
  // Tracked again at T_world_back (the reported pose, at `timestamp`): the lost frames since
  // lost_from_ take the poses interpolated on SE(3), by time, between the frame before them and it.
  void bridgeLostSpan(double timestamp, const SE3& T_world_back);
  // A frame's pose after the last applied correction (the trajectory's).
  SE3 correctedPose(const FrameRef& f) const;
  // On the background thread, after the previous keyframe's check: the loops of keyframe `id`.
  // `localized_from`: the keyframe the run's pose was last found against (the first own
  // keyframe's odometry edge after a saved map's).
  CheckResult check(int id, int localized_from, std::shared_ptr<const KeyframeImages> images, std::vector<SE3> poses);
  // Whether the solve moves some keyframe past slam.min_correction_m / _deg from where it is.
  bool significant(const CheckResult& r) const;
  MapCorrection apply(const CheckResult& r);
  // The graph of every edge so far solved from `poses` (a saved map's keyframes held fixed): after
  // a check's loops, and once more at the run's end.
  std::vector<SE3> solveGraph(const std::vector<SE3>& poses) const;

  const SlamConfig config_;
  const OdometryConfig odometry_;
  const CameraIntrinsics camera_;
  // The tracking thread's: keyframe poses in the tracker's world frame, frames, map anchors.
  std::vector<SE3> poses_;
  std::vector<FrameRef> frames_;
  size_t span_start_ = 0;     // the first frame of the latest keyframe's span
  std::optional<size_t> lost_from_;  // the first frame of the lost span the tracking is in
  std::vector<int> anchors_;  // keyframe per map integration
  int frame_index_ = 0;
  int closures_ = 0;
  int loaded_ = 0;             // keyframes of a saved map: ids 0 .. loaded_ - 1, fixed
  int localized_against_ = -1; // the keyframe the last relocalize() found the pose against
  int corrections_ = 0;
  // Loop edges whose solve was not applied (below slam.min_correction_m / _deg), and finish() called
  // since the last frame: then a last solve is applied whatever it moves, since no tracking follows
  // that it could disturb.
  bool unapplied_loops_ = false;
  bool finishing_ = false;
  // The background checks' (one at a time, in keyframe order): index, images and graph edges.
  FernIndex index_;
  std::vector<std::shared_ptr<const KeyframeImages>> images_;
  std::vector<PoseGraphEdge> edges_;
  // Last: the checks still running end before the members they use go.
  std::deque<Pending> pending_;
};

bool FernLoopCloser::withinKeyframeSpacing(const SE3& T_a_b) const {
  return translationNorm(T_a_b) <= config_.keyframe_translation_m &&
         rotationAngleDeg(T_a_b) <= config_.keyframe_rotation_deg;
}

void FernLoopCloser::waitForChecks() const {
  for (const Pending& p : pending_) p.result.wait();
}

bool FernLoopCloser::needsKeyframe(const SE3& T_world_cam) const {
  return poses_.empty() || !withinKeyframeSpacing(poses_.back().inverse() * T_world_cam);
}

void FernLoopCloser::frameTracked(const TrackedFrameInfo& info) {
  ++frame_index_;
  finishing_ = false;  // the run goes on after a finish() (Python's save): tracking follows again
  if (!info.tracking_ok && !lost_from_) lost_from_ = frames_.size();
  // Before a keyframe made now closes the span the lost frames lie in.
  if (info.tracking_ok && lost_from_) bridgeLostSpan(info.frame->timestamp, info.T_world_cam_reported);
  if (info.tracking_ok && needsKeyframe(info.T_world_cam)) addKeyframe(info);
  const int ref = static_cast<int>(poses_.size()) - 1;
  frames_.push_back({info.frame->timestamp, ref,
                     ref < 0 ? info.T_world_cam_reported : poses_[ref].inverse() * info.T_world_cam_reported,
                     info.T_world_cam_reported});
  if (info.fused) anchors_.push_back(ref);
}

void FernLoopCloser::closeSpan(const SE3& T_world_kf) {
  const int latest = static_cast<int>(poses_.size()) - 1;
  const double frames = static_cast<double>(frames_.size() - span_start_);  // the new keyframe's is next
  for (size_t i = span_start_; latest >= 0 && i < frames_.size(); ++i) {
    FrameRef& f = frames_[i];
    if (f.keyframe != latest) continue;
    f.T_next_cam = T_world_kf.inverse() * poses_[latest] * f.T_kf_cam;
    f.along = static_cast<double>(i - span_start_) / frames;
  }
  span_start_ = frames_.size();
}

void FernLoopCloser::bridgeLostSpan(double timestamp, const SE3& T_world_back) {
  const size_t from = *lost_from_;
  lost_from_.reset();
  if (from == 0) return;  // lost from the first frame handed over: nothing to start from
  // No keyframe is made while lost: the frame before and the lost ones lie in the latest one's span.
  const FrameRef& before = frames_[from - 1];
  const SE3 T_world_before = correctedPose(before);
  const Vector6d step = logSE3(T_world_before.inverse() * T_world_back);
  const double dt_s = timestamp - before.timestamp;
  for (size_t i = from; i < frames_.size(); ++i) {
    FrameRef& f = frames_[i];
    const double along = dt_s > 0 ? std::clamp((f.timestamp - before.timestamp) / dt_s, 0.0, 1.0) : 0.0;
    f.T_world_cam = orthonormalized(T_world_before * expSE3(along * step));
    f.T_kf_cam = f.keyframe < 0 ? f.T_world_cam : poses_[f.keyframe].inverse() * f.T_world_cam;
  }
}

void FernLoopCloser::addKeyframe(const TrackedFrameInfo& info) {
  closeSpan(info.T_world_cam);
  const int id = static_cast<int>(poses_.size());
  poses_.push_back(info.T_world_cam);
  auto images = makeKeyframeImages(*info.frame, camera_, info.scores, config_);
  std::shared_future<CheckResult> previous = pending_.empty() ? std::shared_future<CheckResult>() : pending_.back().result;
  std::shared_future<CheckResult> result =
      std::async(std::launch::async, [this, id, from = localized_against_, images = std::move(images),
                                      poses = poses_, previous]() mutable {
        if (previous.valid()) previous.wait();
        return check(id, from, std::move(images), std::move(poses));
      }).share();
  pending_.push_back({frame_index_ + config_.apply_after_frames, std::move(result)});
}

CheckResult FernLoopCloser::check(int id, int localized_from, std::shared_ptr<const KeyframeImages> images,
                                  std::vector<SE3> poses) {
  // The odometry edge as the tracker measured it, in the poses known when the keyframe was made;
  // the first after a saved map's from the keyframe its pose was found against.
  const int from = id == loaded_ ? localized_from : id - 1;
  if (id > 0 && from >= 0)
    edges_.push_back({from, id, poses[from].inverse() * poses[id], config_.odometry_sigma_m,
                      config_.odometry_sigma_deg * kDeg, config_.odometry_loss_scale});
  std::vector<uint8_t> codes = index_.encode(*images);
  // A saved map's keyframes are candidates however recent.
  const std::vector<PlaceMatch> matches = index_.query(codes, std::max(id - config_.min_keyframe_gap, loaded_ - 1),
                                                       config_.candidates, config_.min_similarity);
  CheckResult result;
  bool covered = false;
  for (const PlaceMatch& m : matches) {
    const SE3 guess = poses[m.keyframe_id].inverse() * poses[id];
    const LoopCheck c = verifyLoop(*images, *images_[m.keyframe_id], guess, odometry_, config_);
    spdlog::debug("loop {} -> {}: similarity {:.2f}, {} (inliers {:.2f}, run back {:.4f} m apart)", id, m.keyframe_id,
                  m.similarity, c.accepted ? "accepted" : c.reason, c.inlier_fraction, c.backward_gap_m);
    if (!c.accepted) continue;
    edges_.push_back({m.keyframe_id, id, c.T_candidate_query, config_.loop_sigma_m, config_.loop_sigma_deg * kDeg,
                      config_.loop_loss_scale});
    ++result.loops;
    covered = covered || withinKeyframeSpacing(c.T_candidate_query);
  }
  // A covered keyframe stays a node of the graph; the older keyframe it matched stands for its view.
  if (covered && config_.cull_covered_keyframes) {
    images_.push_back(nullptr);
  } else {
    index_.add(id, std::move(codes));
    images_.push_back(std::move(images));
  }
  if (result.loops > 0) result.poses = solveGraph(poses);
  return result;
}

std::optional<SE3> FernLoopCloser::relocalize(const RgbdFrame& frame, const cv::Mat& scores) {
  waitForChecks();
  const auto images = makeKeyframeImages(frame, camera_, scores, config_);
  const std::vector<PlaceMatch> matches =
      index_.query(index_.encode(*images), static_cast<int>(images_.size()) - 1, config_.candidates,
                   config_.min_similarity);
  for (const PlaceMatch& m : matches) {
    const LoopCheck c = verifyLoop(*images, *images_[m.keyframe_id], SE3::Identity(), odometry_, config_);
    spdlog::debug("relocalize: keyframe {} similarity {:.2f}: {}", m.keyframe_id, m.similarity,
                  c.accepted ? "accepted" : c.reason);
    if (!c.accepted) continue;
    localized_against_ = m.keyframe_id;
    return orthonormalized(poses_[m.keyframe_id] * c.T_candidate_query);
  }
  return std::nullopt;
}

void FernLoopCloser::loadKeyframes(const std::vector<SavedKeyframe>& keyframes) {
  if (!poses_.empty()) throw InputError("loop closer: a saved map's keyframes come before the run's own");
  for (const SavedKeyframe& k : keyframes) {
    index_.add(static_cast<int>(images_.size()), index_.encode(*k.images));
    images_.push_back(k.images);
    poses_.push_back(k.T_world_kf);
  }
  loaded_ = static_cast<int>(poses_.size());
}

std::vector<SavedKeyframe> FernLoopCloser::savedKeyframes() const {
  waitForChecks();
  std::vector<SavedKeyframe> out;
  out.reserve(poses_.size());
  for (size_t i = 0; i < poses_.size() && i < images_.size(); ++i)
    if (images_[i]) out.push_back({poses_[i], images_[i]});
  return out;
}

int FernLoopCloser::keyframes() const {
  waitForChecks();
  return static_cast<int>(index_.size());
}

std::optional<MapCorrection> FernLoopCloser::takeCorrection() {
  while (!pending_.empty() && pending_.front().due_frame <= frame_index_) {
    const CheckResult r = pending_.front().result.get();
    pending_.pop_front();
    closures_ += r.loops;
    if (r.loops == 0) continue;
    unapplied_loops_ = true;
    if (significant(r)) return apply(r);
  }
  if (finishing_ && pending_.empty() && unapplied_loops_) return apply({0, solveGraph(poses_)});
  return std::nullopt;
}

bool FernLoopCloser::significant(const CheckResult& r) const {
  for (size_t i = 0; i < r.poses.size(); ++i) {
    const SE3 moved = r.poses[i] * poses_[i].inverse();
    if (translationNorm(moved) > config_.min_correction_m || rotationAngleDeg(moved) > config_.min_correction_deg)
      return true;
  }
  return false;
}

std::vector<SE3> FernLoopCloser::solveGraph(const std::vector<SE3>& poses) const {
  PoseGraphOptions options;
  options.fixed_nodes = loaded_;
  return optimizePoseGraph(poses, edges_, options);
}

MapCorrection FernLoopCloser::apply(const CheckResult& r) {
  unapplied_loops_ = false;
  // Keyframes the check knew take its poses; later ones move with the last of those.
  const size_t known = r.poses.size();
  std::vector<SE3> T_new_old(poses_.size());
  for (size_t i = 0; i < poses_.size(); ++i) {
    T_new_old[i] = i < known ? orthonormalized(r.poses[i] * poses_[i].inverse()) : T_new_old[known - 1];
    poses_[i] = orthonormalized(T_new_old[i] * poses_[i]);
  }
  MapCorrection c;
  c.T_new_old_current = T_new_old.back();
  c.T_new_old_by_integration.reserve(anchors_.size());
  for (int a : anchors_) c.T_new_old_by_integration.push_back(a < 0 ? SE3::Identity() : T_new_old[a]);
  ++corrections_;
  return c;
}

SE3 FernLoopCloser::correctedPose(const FrameRef& f) const {
  if (corrections_ == 0 || f.keyframe < 0) return f.T_world_cam;
  // Between two keyframes the frame follows both, by how far along it lies: a jump tracked
  // within the span is spread over it rather than carried whole by the frames after it.
  const SE3 by_before = poses_[f.keyframe] * f.T_kf_cam;
  const SE3 by_next = f.along > 0 ? poses_[f.keyframe + 1] * f.T_next_cam : by_before;
  return orthonormalized(by_before * expSE3(f.along * logSE3(by_before.inverse() * by_next)));
}

Trajectory FernLoopCloser::trajectory() const {
  Trajectory out;
  out.reserve(frames_.size());
  for (const FrameRef& f : frames_) out.push_back({f.timestamp, correctedPose(f)});
  return out;
}

}  // namespace

std::unique_ptr<SlamBackEnd> makeSlamBackEnd(const SlamConfig& config, const OdometryConfig& odometry,
                                             const CameraIntrinsics& camera, std::string* note) {
  switch (config.loop_closure) {
    case LoopClosureMode::Off:
      return nullptr;
    case LoopClosureMode::Ferns:
      if (!loopClosureAvailable()) {
        if (note) *note = "loop closure off: this build has no Ceres (install libceres-dev, scripts/install-deps.sh, and rebuild)";
        return nullptr;
      }
      return std::make_unique<FernLoopCloser>(config, odometry, camera);
  }
  return nullptr;
}

}  // namespace ff

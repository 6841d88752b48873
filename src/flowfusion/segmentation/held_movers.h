#pragma once
// Movers held where they stand once the scores saw them move clearly (our extension;
// scores.hold_seen_moving_s, docs/tuning.md#hold_seen_moving_s). A walker who stops, a person
// standing at the image's border: in a later frame nothing moves, often no mapped background lies
// behind them for the model term, and the map fuses them within a few frames. The hold is 1 where a
// frame saw a mover with a flow of its own off the static map (seenMovingClusters), carried with
// the camera into the next frame as the scores are (carryScores), decaying as exp(-dt / hold_s),
// and let go where the depth no longer shows the surface it held (the mover walked on and the
// background behind it shows). It holds only where the stable map was compared and disagrees: where
// the map holds the pixel, or has nothing there yet (the first frames), a mark seen once on a
// static surface would otherwise be held with the movers. A frame's scores are at least its hold,
// so the odometry and the fusion leave the held mover out too.
#include <limits>
#include <opencv2/core.hpp>

#include "flowfusion/core/camera.h"
#include "flowfusion/core/se3.h"

namespace ff {

class HeldMovers {
 public:
  // hold_s: the decay time in seconds (0: off, nothing is held).
  explicit HeldMovers(double hold_s) : hold_s_(hold_s) {}
  bool enabled() const { return hold_s_ > 0; }

  // The hold in the current frame (CV_32F, `depth`'s size; empty when nothing is held): the one
  // remembered for the frame taken at `previous_timestamp` with `previous_depth` (metres, CV_32F,
  // `camera` at that size), carried by T_prev_cur and decayed over the time to `timestamp`; 0 where
  // the current `depth` has none or lies more than kLetGoFraction of the carried depth plus
  // kLetGoMetres from it, and wherever `map_agreement` (a_M: 1 agrees, 0 disagrees, NaN nothing to
  // compare with) is not below 0.5. Empty when there is no map_agreement (no map yet) or the frame
  // remembered last is not that previous frame.
  cv::Mat carried(const cv::Mat& previous_depth, double previous_timestamp, const CameraIntrinsics& camera,
                  const SE3& T_prev_cur, const cv::Mat& depth, double timestamp, const cv::Mat& map_agreement) const;

  // Remembers the hold of the frame taken at `timestamp`: `carried_hold` (empty: none), and 1
  // where `seen_moving` (CV_8U, > 0; the movers seen moving clearly in that frame) is.
  void remember(const cv::Mat& carried_hold, const cv::Mat& seen_moving, double timestamp);

  // A person standing still sways and breathes by a few centimetres; the background a walker
  // uncovers lies tens of centimetres or more behind them.
  static constexpr float kLetGoFraction = 0.05f;
  static constexpr float kLetGoMetres = 0.02f;

 private:
  double hold_s_;
  cv::Mat hold_;  // CV_32F in [0, 1], the last remembered frame's
  double timestamp_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace ff

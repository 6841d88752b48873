#pragma once
// The result sink behind `flowfusion run --show`: an OpenCV window that shows, as the run goes on,
// the current frame with its dynamic mask, the per-pixel dynamic score and the trajectory so far
// seen from above. It draws on the run's thread (the cost is the drawing and one event poll per
// frame); closing the window stops the drawing, not the run. Without a display (no DISPLAY or
// WAYLAND_DISPLAY) it draws nothing and says so in the run's notes.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "flowfusion/pipeline/result_sink.h"

namespace ff {

struct ViewerOptions {
  std::string window = "flowfusion";
  int panel_height_px = 300;  // each of the three panels, side by side
};

class ViewerSink : public ResultSink {
 public:
  explicit ViewerSink(ViewerOptions options = {});
  void begin(const RunInfo& info) override;
  void frame(const RgbdFrame& frame, const FrameResult& result) override;
  void end(RunSummary& summary, const StaticMap* map) override;

  // The image last shown (empty before the first frame or without a display), and how many were.
  const cv::Mat& lastImage() const { return last_; }
  size_t framesShown() const { return shown_; }

 private:
  cv::Mat trajectoryPanel(cv::Size size) const;

  ViewerOptions options_;
  bool has_display_ = false;
  bool open_ = false;  // the window is up (false once a user closed it)
  bool closed_by_user_ = false;
  size_t shown_ = 0;
  cv::Mat last_;
  std::vector<Eigen::Vector2d> path_xy_;  // camera positions seen from above (world x, y), metres
};

// Whether a window can be opened here (DISPLAY or WAYLAND_DISPLAY set).
bool displayAvailable();

}  // namespace ff

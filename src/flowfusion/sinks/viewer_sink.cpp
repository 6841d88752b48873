#include "flowfusion/sinks/viewer_sink.h"

#include <algorithm>
#include <cstdlib>
#include <opencv2/highgui.hpp>
#include <opencv2/imgproc.hpp>

#include "flowfusion/visualization/overlay.h"

namespace ff {
namespace {

cv::Mat fitHeight(const cv::Mat& bgr, int height) {
  cv::Mat out;
  const double f = static_cast<double>(height) / std::max(1, bgr.rows);
  cv::resize(bgr, out, cv::Size(std::max(1, static_cast<int>(bgr.cols * f)), height), 0, 0, cv::INTER_AREA);
  return out;
}

void label(cv::Mat& img, const std::string& text) {
  cv::putText(img, text, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255), 2, cv::LINE_AA);
  cv::putText(img, text, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(30, 30, 30), 1, cv::LINE_AA);
}

// The per-pixel dynamic score (0 black .. 1 yellow), or a note when segmentation is off.
cv::Mat scorePanel(const cv::Mat& scores, cv::Size size) {
  if (scores.empty()) {
    cv::Mat blank(size, CV_8UC3, cv::Scalar(40, 40, 40));
    label(blank, "no scores (segmentation off)");
    return blank;
  }
  cv::Mat u8, colour;
  scores.convertTo(u8, CV_8U, 255.0);
  cv::applyColorMap(u8, colour, cv::COLORMAP_INFERNO);
  cv::resize(colour, colour, size, 0, 0, cv::INTER_NEAREST);
  label(colour, "dynamic score");
  return colour;
}

}  // namespace

bool displayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

ViewerSink::ViewerSink(ViewerOptions options) : options_(std::move(options)) {}

void ViewerSink::begin(const RunInfo&) {
  has_display_ = displayAvailable();
  if (!has_display_) return;
  cv::namedWindow(options_.window, cv::WINDOW_AUTOSIZE);
  open_ = true;
}

cv::Mat ViewerSink::trajectoryPanel(cv::Size size) const {
  cv::Mat panel(size, CV_8UC3, cv::Scalar(250, 250, 250));
  label(panel, "path from above (x, y)");
  if (path_xy_.empty()) return panel;
  Eigen::Vector2d lo = path_xy_.front(), hi = lo;
  for (const auto& p : path_xy_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 0.05});  // metres, at least 5 cm
  const double scale = 0.8 * std::min(size.width, size.height) / span;
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(size.width / 2 + (p.x() - centre.x()) * scale),
                     static_cast<int>(size.height / 2 - (p.y() - centre.y()) * scale));
  };
  for (size_t i = 1; i < path_xy_.size(); ++i)
    cv::line(panel, px(path_xy_[i - 1]), px(path_xy_[i]), cv::Scalar(26, 140, 255), 2, cv::LINE_AA);
  cv::circle(panel, px(path_xy_.back()), 5, cv::Scalar(40, 40, 200), cv::FILLED, cv::LINE_AA);
  return panel;
}

void ViewerSink::frame(const RgbdFrame& frame, const FrameResult& result) {
  if (result.has_pose) path_xy_.emplace_back(result.T_world_cam.translation().x(), result.T_world_cam.translation().y());
  if (!open_) return;
  if (shown_ > 0 && cv::getWindowProperty(options_.window, cv::WND_PROP_VISIBLE) < 1) {
    open_ = false;  // closed by the user: the run goes on without drawing
    closed_by_user_ = true;
    return;
  }
  const int h = options_.panel_height_px;
  cv::Mat left = fitHeight(result.dynamic_mask.empty() ? frame.color : overlayMask(frame.color, result.dynamic_mask), h);
  label(left, "frame with its dynamic mask" + std::string(result.tracking_ok ? "" : " (TRACKING LOST)"));
  const cv::Mat middle = scorePanel(result.scores, left.size());
  const cv::Mat right = trajectoryPanel(cv::Size(h, h));
  cv::hconcat(std::vector<cv::Mat>{left, middle, right}, last_);
  cv::imshow(options_.window, last_);
  cv::waitKey(1);
  ++shown_;
}

void ViewerSink::end(RunSummary& summary, const StaticMap*) {
  if (!has_display_) {
    summary.notes.push_back("--show: no display (DISPLAY and WAYLAND_DISPLAY are unset), nothing shown");
    return;
  }
  if (open_) cv::destroyWindow(options_.window);
  if (closed_by_user_) summary.notes.push_back("--show: the window was closed during the run");
  open_ = false;
}

}  // namespace ff

#pragma once
// The depth sensor's invalid band: the lines at the image's edges where a registered depth image has
// no depth for anything (the depth camera sees less than the colour camera). The segmentation keeps
// its hole rules off it; `augment` can leave its movers without depth there, as the sensor would.
#include <array>
#include <opencv2/core.hpp>
#include <vector>

namespace ff {

// The sensor's invalid band, by its width in lines at each edge (rows at the top and the bottom,
// columns at the left and the right): the lines from the edge inward, up to a tenth of the image, of
// which at least kBandMinShare lack depth (TUM fr1 as loaded, undistorted, at 640x480: about 45 rows at
// the top, 12 columns at the left and 50 at the right). A mover `augment` draws there with its
// depth (BandDepth::Drawn) narrows a frame's band, hence a share below 0.9.
struct SensorBand {
  int top = 0, bottom = 0, left = 0, right = 0;  // lines

  static SensorBand of(const cv::Mat& depth);  // one frame's (CV_32F, metres)
  cv::Mat pixels(cv::Size size) const;         // CV_8U, 255 on the band
};

// The band of a run's frames: per edge, the median of the frames' widths. The sensor's own band is
// in nearly every frame; a surface nearer than the sensor's range at the border widens some frames'
// (xyz_near's box face over the left third of the view), a mover in front of the band narrows some.
class SensorBandMedian {
 public:
  void add(const SensorBand& frame_band);
  SensorBand median() const;  // all 0 before the first frame

 private:
  std::array<std::vector<int>, 4> counts_;  // per edge (top, bottom, left, right): frames per width
  int frames_ = 0;
};
constexpr float kBandMinShare = 0.6f;
constexpr int kBandMaxFraction = 10;

}  // namespace ff

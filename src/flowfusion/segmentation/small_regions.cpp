#include "flowfusion/segmentation/small_regions.h"

#include <opencv2/imgproc.hpp>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/region_labels.h"

namespace ff {

void dropSmallInteriorRegions(cv::Mat& mask, double min_area_share) {
  if (mask.empty() || mask.type() != CV_8UC1)
    throw InputError("dropSmallInteriorRegions: the mask must be a non-empty CV_8UC1 image");
  if (!(min_area_share >= 0 && min_area_share < 1))
    throw InputError("dropSmallInteriorRegions: min_area_share must be in [0, 1)");
  if (min_area_share == 0) return;
  cv::Mat regions, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask > 0, regions, stats, centroids, 8, CV_32S);
  const double min_area = min_area_share * static_cast<double>(mask.total());
  std::vector<uchar> drop(n, 0);
  bool any = false;
  for (int r = 1; r < n; ++r) {
    const int x = stats.at<int>(r, cv::CC_STAT_LEFT), y = stats.at<int>(r, cv::CC_STAT_TOP);
    const int w = stats.at<int>(r, cv::CC_STAT_WIDTH), h = stats.at<int>(r, cv::CC_STAT_HEIGHT);
    const bool on_border = x == 0 || y == 0 || x + w == mask.cols || y + h == mask.rows;
    drop[r] = !on_border && stats.at<int>(r, cv::CC_STAT_AREA) < min_area;
    any = any || drop[r];
  }
  if (any) setChosenRegions(mask, regions, drop, 0);
}

}  // namespace ff

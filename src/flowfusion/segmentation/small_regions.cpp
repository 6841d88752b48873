#include "flowfusion/segmentation/small_regions.h"

#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/error.h"
#include "flowfusion/segmentation/region_labels.h"

namespace ff {

void dropSmallInteriorRegions(cv::Mat& mask, double min_area_share, const cv::Mat& keep) {
  if (mask.empty() || mask.type() != CV_8UC1)
    throw InputError("dropSmallInteriorRegions: the mask must be a non-empty CV_8UC1 image");
  if (!(min_area_share >= 0 && min_area_share < 1))
    throw InputError("dropSmallInteriorRegions: min_area_share must be in [0, 1)");
  if (!keep.empty() && (keep.type() != CV_8UC1 || keep.size() != mask.size()))
    throw InputError("dropSmallInteriorRegions: keep must be a CV_8UC1 image of the mask's size");
  if (min_area_share == 0) return;
  cv::Mat regions, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask > 0, regions, stats, centroids, 8, CV_32S);
  const double min_area = min_area_share * static_cast<double>(mask.total());
  const std::vector<int> kept = pixelsPerRegionWhere(regions, n, keep);
  std::vector<uchar> drop(n, 0);
  bool any = false;
  for (int r = 1; r < n; ++r) {
    const int x = stats.at<int>(r, cv::CC_STAT_LEFT), y = stats.at<int>(r, cv::CC_STAT_TOP);
    const int w = stats.at<int>(r, cv::CC_STAT_WIDTH), h = stats.at<int>(r, cv::CC_STAT_HEIGHT);
    const int area = stats.at<int>(r, cv::CC_STAT_AREA);
    const bool on_border = x == 0 || y == 0 || x + w == mask.cols || y + h == mask.rows;
    drop[r] = !on_border && area < min_area && 2 * kept[r] <= area;
    any = any || drop[r];
  }
  if (any) setChosenRegions(mask, regions, drop, 0);
}

cv::Mat seenMovingClusters(const ClusterGraph& graph, const ResidualImages& residuals, const DynamicScores& scores,
                           double min_flow_px, double max_map_agreement) {
  const int n = graph.num_clusters;
  if (static_cast<int>(scores.moving.size()) != n)
    throw InputError("seenMovingClusters: " + std::to_string(scores.moving.size()) + " moving flags for " +
                     std::to_string(n) + " clusters");
  std::vector<float> seen(n, 0.f);
  if (min_flow_px > 0) {
    const ClusterMeans r_F = clusterMeans(graph, residuals.r_F, "r_F");
    const ClusterMeans a_M = clusterMeans(graph, residuals.a_M, "a_M");
    for (int c = 0; c < n; ++c)
      seen[c] = scores.moving[c] && r_F.has(c) && r_F.mean(c) >= min_flow_px &&
                !(a_M.has(c) && a_M.mean(c) >= max_map_agreement);
  }
  return dynamicMask(clusterValues(graph, seen, "seenMovingClusters"), 0.5f);
}

}  // namespace ff

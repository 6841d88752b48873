#include "flowfusion/segmentation/map_agreement_mask.h"

#include <opencv2/imgproc.hpp>

#include "flowfusion/core/error.h"

namespace ff {

void clearMapAgreement(cv::Mat& mask, const cv::Mat& agreement) {
  if (mask.empty() || mask.type() != CV_8UC1)
    throw InputError("clearMapAgreement: the mask must be a non-empty CV_8UC1 image");
  if (agreement.empty()) return;
  if (agreement.type() != CV_8UC1) throw InputError("clearMapAgreement: the agreement must be a CV_8UC1 image");
  cv::Mat at_mask_size = agreement;
  if (agreement.size() != mask.size()) cv::resize(agreement, at_mask_size, mask.size(), 0, 0, cv::INTER_NEAREST);
  mask.setTo(0, at_mask_size);
}

}  // namespace ff

#pragma once
// Place recognition without trained models: randomized ferns on small images (Glocker et al.,
// "Real-time RGB-D camera relocalization via randomized ferns", TVCG 2015; ElasticFusion's
// loop and relocalization index). Each fern is one pixel of the small image tested against four
// random thresholds, one per channel (blue, green, red, depth); its 4-bit code is compared between
// images. A fern whose pixel is dynamic or has no depth (KeyframeImages::small_depth holds 0
// there) is unknown, and two images are compared over the ferns known in both, so a person in
// either image neither adds nor removes agreement.
#include <cstdint>
#include <vector>

#include "flowfusion/slam/keyframe.h"

namespace ff {

struct PlaceMatch {
  int keyframe_id = -1;
  // Share of the ferns known in both that agree, [0, 1], each weighted by how rare the query's code
  // is among the indexed keyframes (a plain wall's code, common to most, counts little).
  double similarity = 0;
  int compared = 0;       // ferns known in both
};

class FernIndex {
 public:
  // Ferns on images of `size` (the small images of KeyframeImages), depth thresholds in
  // [min_depth_m, max_depth_m]; the same seed gives the same ferns.
  FernIndex(int fern_count, cv::Size size, double min_depth_m, double max_depth_m, uint64_t seed = 1);

  // One code per fern, kUnknown where its pixel is dynamic or has no depth.
  std::vector<uint8_t> encode(const KeyframeImages& images) const;
  void add(int keyframe_id, std::vector<uint8_t> codes);
  // The best `count` keyframes with id <= max_id (most similar first) whose similarity reaches
  // min_similarity over at least a quarter of the ferns.
  std::vector<PlaceMatch> query(const std::vector<uint8_t>& codes, int max_id, int count,
                                double min_similarity) const;
  size_t size() const { return entries_.size(); }

  static constexpr uint8_t kUnknown = 0xFF;

 private:
  struct Fern {
    int x = 0, y = 0;
    uint8_t bgr[3] = {0, 0, 0};
    float depth_m = 0;
  };
  struct Entry {
    int keyframe_id;
    std::vector<uint8_t> codes;
  };
  cv::Size size_;
  std::vector<Fern> ferns_;
  std::vector<Entry> entries_;
  std::vector<int> code_counts_;  // per fern and code (fern * 16 + code): indexed keyframes with it
};

}  // namespace ff

#include "flowfusion/slam/place_index.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "flowfusion/core/error.h"

namespace ff {

namespace {
// Colour thresholds where indoor colours lie: a threshold near black or white splits nothing.
constexpr double kMinColour = 30, kMaxColour = 225;
}  // namespace

FernIndex::FernIndex(int fern_count, cv::Size size, double min_depth_m, double max_depth_m, uint64_t seed)
    : size_(size) {
  std::mt19937_64 rng(seed);
  // Hand-written draws: the standard distributions differ between standard libraries.
  const auto uniform = [&rng](double lo, double hi) { return lo + (hi - lo) * ((rng() >> 11) * 0x1.0p-53); };
  ferns_.resize(fern_count);
  code_counts_.assign(static_cast<size_t>(fern_count) * 16, 0);
  for (Fern& f : ferns_) {
    f.x = std::min(size.width - 1, static_cast<int>(uniform(0, size.width)));
    f.y = std::min(size.height - 1, static_cast<int>(uniform(0, size.height)));
    for (uint8_t& c : f.bgr) c = static_cast<uint8_t>(uniform(kMinColour, kMaxColour));
    f.depth_m = static_cast<float>(uniform(min_depth_m, max_depth_m));
  }
}

std::vector<uint8_t> FernIndex::encode(const KeyframeImages& images) const {
  if (images.small_bgr.size() != size_ || images.small_depth.size() != size_)
    throw InputError("FernIndex: keyframe images are " + std::to_string(images.small_bgr.cols) + "x" +
                     std::to_string(images.small_bgr.rows) + ", the index's " + std::to_string(size_.width) +
                     "x" + std::to_string(size_.height));
  std::vector<uint8_t> codes(ferns_.size(), kUnknown);
  for (size_t i = 0; i < ferns_.size(); ++i) {
    const Fern& f = ferns_[i];
    const float depth = images.small_depth.at<float>(f.y, f.x);
    if (!(depth > 0)) continue;
    const cv::Vec3b bgr = images.small_bgr.at<cv::Vec3b>(f.y, f.x);
    codes[i] = static_cast<uint8_t>((bgr[0] > f.bgr[0]) | (bgr[1] > f.bgr[1]) << 1 | (bgr[2] > f.bgr[2]) << 2 |
                                    (depth > f.depth_m) << 3);
  }
  return codes;
}

void FernIndex::add(int keyframe_id, std::vector<uint8_t> codes) {
  if (codes.size() != ferns_.size()) throw InputError("FernIndex::add: codes of another index");
  for (size_t i = 0; i < codes.size(); ++i)
    if (codes[i] != kUnknown) ++code_counts_[i * 16 + codes[i]];
  entries_.push_back({keyframe_id, std::move(codes)});
}

std::vector<PlaceMatch> FernIndex::query(const std::vector<uint8_t>& codes, int max_id, int count,
                                         double min_similarity) const {
  if (codes.size() != ferns_.size()) throw InputError("FernIndex::query: codes of another index");
  const int min_compared = static_cast<int>(ferns_.size() / 4);
  // A code most keyframes share (a plain wall's) says little: each fern's agreement counts with
  // the rarity of the query's code among the indexed keyframes, log((N + 1) / (n + 1)).
  std::vector<double> weight(codes.size(), 0.0);
  const double n = static_cast<double>(entries_.size());
  for (size_t i = 0; i < codes.size(); ++i)
    if (codes[i] != kUnknown) weight[i] = std::log((n + 1) / (code_counts_[i * 16 + codes[i]] + 1));
  std::vector<PlaceMatch> matches;
  for (const Entry& e : entries_) {
    if (e.keyframe_id > max_id) continue;
    int compared = 0;
    double agree = 0, total = 0;
    for (size_t i = 0; i < codes.size(); ++i) {
      if (codes[i] == kUnknown || e.codes[i] == kUnknown) continue;
      ++compared;
      total += weight[i];
      if (codes[i] == e.codes[i]) agree += weight[i];
    }
    if (compared < min_compared || total <= 0) continue;
    const double similarity = agree / total;
    if (similarity >= min_similarity) matches.push_back({e.keyframe_id, similarity, compared});
  }
  // Ties by id, so the order never depends on the sort's implementation.
  std::sort(matches.begin(), matches.end(), [](const PlaceMatch& a, const PlaceMatch& b) {
    return a.similarity != b.similarity ? a.similarity > b.similarity : a.keyframe_id < b.keyframe_id;
  });
  if (static_cast<int>(matches.size()) > count) matches.resize(count);
  return matches;
}

}  // namespace ff

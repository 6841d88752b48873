// StaticMap::moveSurfels: the map follows a loop closure (slam/loop_closer.h), each surfel with the
// keyframe its creating integration was anchored to; StaticMap::loadSurfels: a saved map's surfels.
#include "flowfusion/fusion/static_map.h"

namespace ff {

void StaticMap::moveSurfels(const std::vector<SE3>& T_new_old_by_integration) {
  const int known = static_cast<int>(T_new_old_by_integration.size());
  for (Surfel& s : surfels_) {
    if (s.created < 0 || s.created >= known) continue;
    const SE3& T = T_new_old_by_integration[s.created];
    s.position = (T * s.position.cast<double>()).cast<float>();
    s.normal = (T.linear() * s.normal.cast<double>()).normalized().cast<float>();
  }
}

void StaticMap::loadSurfels(const std::vector<Surfel>& surfels) {
  for (const Surfel& loaded : surfels) {
    if (surfels_.size() >= static_cast<size_t>(config_.max_surfels)) {
      budget_reached_ = true;
      return;
    }
    Surfel& s = surfels_.emplace_back(loaded);
    s.created = s.last_seen = -1;
    s.removal_votes = 0;
  }
}

}  // namespace ff

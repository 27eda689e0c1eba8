#include "server/raycast/preintegrated_lut_cache.h"

#include <algorithm>

#include "server/raycast/preintegrated_lut.h"

namespace vpm {

PreintegratedLutCache::PreintegratedLutCache(size_t capacity)
    : capacity_(std::max<size_t>(capacity, 1)) {}

const std::vector<glm::vec4>& PreintegratedLutCache::Table(const RenderPreset& preset,
                                                           double step_mm) {
  const auto hit = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) {
    return e.step_mm == step_mm && e.preset == preset;
  });
  if (hit != entries_.end()) {
    entries_.splice(entries_.begin(), entries_, hit);
    return entries_.front().table;
  }
  entries_.push_front({preset, step_mm, BakePreintegratedLut(preset, step_mm)});
  ++bakes_;
  if (entries_.size() > capacity_) entries_.pop_back();
  return entries_.front().table;
}

}  // namespace vpm

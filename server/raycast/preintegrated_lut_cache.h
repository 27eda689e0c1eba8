// The last few pre-integrated tables a renderer baked, keyed by preset and
// step (mm). A session's frames alternate between a few steps: the
// interactive step while the pointer moves, the refinement rung's and the
// still's at rest (refine_ladder.h). Baking a table takes 8-13 ms on one
// core (BakePreintegratedLut, 256^2 segments); each baked once per preset
// and step is then uploaded as it is, not baked again at every change of
// quality (docs/RENDERING.md, "Sampling").
#pragma once

#include <cstddef>
#include <list>
#include <vector>

#include <glm/glm.hpp>

#include "server/raycast/render_presets.h"

namespace vpm {

class PreintegratedLutCache {
 public:
  // Three: the interactive step, one rung, the still.
  static constexpr size_t kDefaultCapacity = 3;
  explicit PreintegratedLutCache(size_t capacity = kDefaultCapacity);

  // BakePreintegratedLut(preset, step_mm), baked now or kept from an
  // earlier call with an equal preset and the same step. The reference
  // holds until the next call. Evicts the least recently used beyond the
  // capacity (each table is 1 MiB).
  const std::vector<glm::vec4>& Table(const RenderPreset& preset, double step_mm);

  size_t bakes() const { return bakes_; }  // tables baked since construction

 private:
  struct Entry {
    RenderPreset preset;
    double step_mm;
    std::vector<glm::vec4> table;
  };
  size_t capacity_;
  std::list<Entry> entries_;  // most recently used first
  size_t bakes_ = 0;
};

}  // namespace vpm

// The flags that choose what part of the deformed volume a frame shows,
// shared by the commands that render (`vpm render`, `vpm slice`):
//   --crop X0 Y0 Z0 X1 Y1 Z1   a box, world (LPS) mm
//   --clip NX NY NZ D          keeps dot(n, x) >= D (world mm); repeatable
//   --cut auto|on|off          the view cut (SceneView::view_cut); auto: on
//                              unless --crop or --clip is given
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "server/common/status.h"
#include "server/raycast/clip_region.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::cli {

struct ClipFlags {
  std::vector<double> crop;                // empty or 6 numbers
  std::vector<std::vector<double>> clip;   // 4 numbers each
  std::string cut = "auto";
};

void AddClipFlags(CLI::App* app, ClipFlags* flags);

struct ClipChoice {
  ClipRegion region;
  bool view_cut = false;
};
// InvalidArgument names the flag that is wrong.
Result<ClipChoice> ToClipChoice(const ClipFlags& flags);

// The same choice as RenderSettings fields (crop, clip, view_cut).
void FillClipSettings(const ClipChoice& choice, v3::RenderSettings* settings);

}  // namespace vpm::cli

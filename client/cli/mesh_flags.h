// The mesh-building flags shared by `vpm mesh`, `vpm compare-meshes` and
// (later) `vpm render`. The flag names are the interface.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "server/common/status.h"
#include "server/mesh/build_proxy_mesh.h"

namespace vpm::cli {

struct MeshFlags {
  std::vector<int64_t> grid{20, 20, 20};
  int64_t target = 250;
  std::string footprint = "point";
  std::string density_mode = "spread";
  double wg = 1.0, wd = 0.5, radius_factor = 2.0;
  std::string tf = "auto";
  double bone = 250.0, influence_threshold = 100.0, influence_factor = 0.75;
  std::vector<double> refine_at;  // empty or X Y Z (mm, world LPS)
  std::string refine_at_landmark; // or a landmark of the volume (phantoms have them)
  double roi_factor = 1.5;
  int64_t refine_count = 150;
  double steiner_min_dihedral = 5.0;  // degrees; 0: no Steiner points
};

void AddMeshFlags(CLI::App* app, MeshFlags* flags);
// `volume` resolves --refine-at-landmark.
Result<MeshParams> ToMeshParams(const MeshFlags& flags, const Volume& volume);
// The transfer-function presets, one per line, for --help.
std::string TransferFunctionHelp();

}  // namespace vpm::cli

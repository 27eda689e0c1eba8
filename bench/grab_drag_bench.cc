// What a grab takes and what one drag does with it, per volume and
// footprint: the handles, the fixed (hard) vertices inside the grab radius,
// the deformable ones left free because they touch a fixed vertex, then the
// largest vertex displacement against the drag, the inverted tets and
// whether the solver had to force the step. The drag is taken as `vpm
// render` takes it by default: one Drag call (--increments N: N calls, as a
// user drags) in the interactive settings (SolverOptions defaults), the grab
// radius h (the CLI's default).
//
// The cases: the service process test's small phantom mesh
// (phantom:abdomen?size=48, 10^3 lattice to 60 vertices), the default
// phantom mesh at 128^3, both grabbed at left_renal_artery and dragged 12 mm
// cranially; the Colin27 T1 MRI grabbed at its box centre and the
// gantry-tilted head CT of the demo (tests/data/ct-philips-tilt, at (123,
// 145, 64) mm), dragged 12 mm.
//
// Usage: grab_drag_bench [--radius-factor F] [--drag-mm D] [--increments N]
//                        [SOURCE_DIR]
//   SOURCE_DIR: the repository root (for tests/data), default ".".
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "bench/explain_inverted_tets.h"
#include "server/fem/fem_model.h"
#include "server/io/read_volume.h"
#include "server/mesh/build_proxy_mesh.h"

using namespace vpm;

namespace {

struct Case {
  std::string name;
  std::string source;
  std::string tf;                       // "" = the default
  std::array<int64_t, 3> grid{20, 20, 20};
  int64_t target = 250;
  std::string landmark;                 // grab here when set
  std::optional<glm::dvec3> grab_mm;    // else here, else the box centre
};

glm::dvec3 GrabPoint(const Case& c, const Volume& volume) {
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == c.landmark) return l.position_mm;
  }
  return c.grab_mm.value_or(volume.geometry().extent_mm() * 0.5);
}

void Row(const Case& c, const Volume& volume, Footprint footprint, double radius_factor,
         double drag_mm, int increments) {
  MeshParams params;
  params.footprint = footprint;
  params.grid = c.grid;
  params.target = c.target;
  if (!c.tf.empty()) params.tf = c.tf;
  const glm::dvec3 grab = GrabPoint(c, volume);
  params.refine_at_mm = grab;
  const ProxyMesh mesh = bench::Check(BuildProxyMesh(volume, params), "build");
  FemModel model =
      bench::Check(FemModel::Create(mesh, volume.geometry().extent_mm()), "fem");
  const double radius = radius_factor * mesh.stats.h_mm;
  const GrabInfo info = bench::Check(model.Grab(grab, radius), "grab");
  bool forced = false;
  for (int i = 1; i <= increments; ++i) {
    const double fraction = static_cast<double>(i) / increments;
    const SolveStats s =
        bench::Check(model.Drag(glm::dvec3(0.0, 0.0, drag_mm * fraction)), "drag");
    forced |= s.forced_inversion;
  }
  if (std::getenv("GRAB_DRAG_EXPLAIN") != nullptr) bench::ExplainInvertedTets(model, volume, grab);
  const double max_u = model.MaxDisplacementMm();
  std::printf("%-14s %-6s %5zu %6.1f %7zu %6lld %6lld %9.2f %7.3f %5lld %6s\n", c.name.c_str(),
              FootprintName(footprint), mesh.vertices.size(), radius, info.handles.size(),
              static_cast<long long>(info.fixed_within),
              static_cast<long long>(info.left_free_next_to_fixed), max_u, max_u / drag_mm,
              static_cast<long long>(model.CountInvertedTets()),
              forced ? "yes" : "no");
}

}  // namespace

int main(int argc, char** argv) {
  double radius_factor = 1.0;
  double drag_mm = 12.0;
  int increments = 1;
  std::string root = ".";
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--radius-factor") == 0 && i + 1 < argc) {
      radius_factor = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--drag-mm") == 0 && i + 1 < argc) {
      drag_mm = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--increments") == 0 && i + 1 < argc) {
      increments = std::max(1, std::atoi(argv[++i]));
    } else {
      root = argv[i];
    }
  }
  std::vector<Case> cases = {
      {"phantom48", "phantom:abdomen?size=48", "", {10, 10, 10}, 60, "left_renal_artery", {}},
      {"phantom128", "phantom:abdomen?size=128", "", {20, 20, 20}, 250, "left_renal_artery", {}},
      {"mri-colin27", "/usr/share/mricron/templates/ch2.nii.gz", "mri-t1", {20, 20, 20}, 250, "",
       {}},
      {"ct-tilt", root + "/tests/data/ct-philips-tilt", "", {20, 20, 18}, 250, "",
       glm::dvec3(123.0, 145.0, 64.0)},
  };
  std::printf("a drag of %.1f mm (+z) in %d increment(s), grab radius %.2f h, interactive "
              "solver settings\n", drag_mm, increments, radius_factor);
  std::printf("%-14s %-6s %5s %6s %7s %6s %6s %9s %7s %5s %6s\n", "case", "foot", "verts",
              "r mm", "handles", "fixed", "freed", "max|u| mm", "/drag", "inv", "forced");
  for (const Case& c : cases) {
    if (c.source.find(':') == std::string::npos && !std::filesystem::exists(c.source)) {
      std::printf("%-14s (missing: %s)\n", c.name.c_str(), c.source.c_str());
      continue;
    }
    const Volume volume = bench::Check(ReadVolume(c.source, VolumeLimits{}), "read");
    for (Footprint f : {Footprint::kPoint, Footprint::kCell}) {
      Row(c, volume, f, radius_factor, drag_mm, increments);
    }
  }
  return 0;
}

// The deformation measures of docs/ALGORITHM.md section 6, for meshes of one
// vertex budget under one standard drag:
//  - deformation error: RMS (and max) over the body voxels (TF > 0) of the
//    displacement interpolated on the mesh minus the displacement of a
//    reference solved on the full dense lattice (all G vertices kept);
//  - rigidity: the largest displacement of any bone voxel (value above the
//    bone threshold) as a fraction of the drag;
//  - validity: inverted tets after the standard drag and after a drag of
//    1.5 h in the same direction.
// Voxels are sampled every `voxel_stride` voxels per axis (default 4: 1/64
// of the voxels), which is documented with the figures.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/fem/fem_model.h"
#include "server/mesh/build_proxy_mesh.h"

namespace vpm {

// The standard drag (docs/MESH.md, "The standard drag"): grab the phantom's
// left kidney centre (medulla, 59 HU: deformable under both rules of section
// 3) with a radius of half a lattice step h and drag it 12 mm anteriorly
// (-y, towards the surgeon, as a retraction), through the perirenal fat.
// The renal artery is no fit: section 3's influence rule makes its vertices
// near the spine hard, so a grab there holds fixed vertices.
struct StandardDrag {
  std::string landmark = "left_kidney_center";
  // The grab point itself (physical voxel space, mm), for volumes without
  // landmarks; when set, `landmark` is not looked up.
  std::optional<glm::dvec3> point_mm;
  glm::dvec3 offset_mm{0.0, -12.0, 0.0};
  double grab_radius_factor = 0.5;  // x h of the G lattice
};

struct DeformationMeasure {
  std::string name;  // "regular", "step 2", "step 4", "reference"
  int64_t vertices = 0;
  int64_t handles = 0;
  double min_dihedral_deg = 0.0;  // smallest dihedral angle of the rest mesh, degrees
  double rms_error_mm = 0.0;  // vs the reference, over sampled body voxels
  double max_error_mm = 0.0;
  double bone_max_fraction = 0.0;  // max bone-voxel displacement / |drag|
  glm::dvec3 bone_worst_mm{0.0};   // where that bone voxel is (physical mm)
  int64_t inverted_at_drag = 0;    // inverted tets after the standard drag
  int64_t inverted_at_1_5h = 0;    // after a drag of 1.5 h
  // The prescribed drag itself flattened a tet (SolveStats::forced_inversion:
  // e.g. two handles and a fixed vertex in one tet), so the barrier could
  // not keep every tet positive.
  bool forced_at_drag = false;
  bool forced_at_1_5h = false;
  double solve_ms = 0.0;  // FEM for the standard drag
  bool converged = false;
};

// Solver settings for measuring: solved close to equilibrium (update 1e-4 of
// the motion, inner PCG to 1e-2), not the interactive defaults (5%, 0.2), so
// that the error compares meshes, not solver paths. At 128^3 the table is the
// same to 3 decimals with 1e-6 and 1e-4 (5x the FEM time). A jump the
// inversion barrier cannot take at once goes in up to 64 load steps, each
// brought to equilibrium (the interactive defaults: 4 steps, 1 iteration
// between them).
inline FemOptions MeasurementFemOptions() {
  FemOptions options;
  options.solver.update_tolerance = 1e-4;
  options.solver.cg_tolerance = 1e-2;
  options.solver.max_newton_iterations = 200;
  options.solver.max_load_steps = 64;
  options.solver.intermediate_newton_iterations = 200;
  return options;
}

struct DeformationOptions {
  int voxel_stride = 4;
  FemOptions fem = MeasurementFemOptions();
};

// Rows: reference (the dense lattice), regular, step 2, step 4. The budget is
// params.target + the number of refinement vertices step 4 accepted.
Result<std::vector<DeformationMeasure>> CompareDeformation(const Volume& volume,
                                                           const MeshParams& params,
                                                           const StandardDrag& drag,
                                                           const DeformationOptions& options = {});

}  // namespace vpm

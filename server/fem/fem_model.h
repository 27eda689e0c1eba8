// FEM on a volume proxy mesh with manipulation (docs/ALGORITHM.md section 5):
// grab vertices near a point, drag them (prescribed displacement) or pull
// them (force), release back to rest. Units: mm, N, E in kPa at the API
// (fem_units.h).
//
// Constraints: skeleton vertices and anchors fixed, box-face vertices fixed
// along their face normal (FixedDofs); other hard vertices are free.
// Material: E_soft everywhere, E_hard in every tet touching a hard vertex
// (TetYoungModuli).
//
// Handles are attached in one of two ways (FemOptions::attachment): prescribed
// (the paper's drag, kept for the section-6 measures) or by stiff springs
// towards their targets (the interactive default): the inversion barrier
// then always wins against a spring, so no tet inverts whatever the drag,
// and the handles lag where the tissue cannot follow. With springs, a drag
// can be kept on release and pins hold tissue still (held springs); Reset
// returns to rest. Tets that are flat to
// round-off are left out of the FEM (flat_tets.h); a vertex left in no tet
// is fixed.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/fem/corotational_solver.h"
#include "server/fem/fem_material.h"
#include "server/fem/find_handles.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

enum class HandleAttachment { kPrescribed, kSpring };

struct FemOptions {
  FemMaterial material;
  SolverOptions solver;
  HandleAttachment attachment = HandleAttachment::kPrescribed;
  // kSpring: each handle DOF's spring stiffness is this multiple of the DOF's
  // rest-stiffness diagonal (dimensionless). 100 keeps a handle in soft
  // tissue within about 1% of its target (docs/FEM.md, "Spring handles").
  double spring_factor = 100.0;
};

// The interactive scene's settings (DeformableScene): the solver's
// interactive tolerances with the per-event work bound
// (kInteractiveEventNewtonBudget; docs/FEM.md, "Per-event work bound"). A
// Drag may then stop short of its offset; later Drags or Settle go on.
inline FemOptions InteractiveFemOptions() {
  FemOptions options;
  options.solver.event_newton_budget = kInteractiveEventNewtonBudget;
  options.solver.event_max_lag_shares = kInteractiveMaxLagShares;
  options.attachment = HandleAttachment::kSpring;
  return options;
}

struct FemSetupStats {
  double assembly_ms = 0.0;  // elements and the rest stiffness
  double factor_ms = 0.0;    // SimplicialLDLT of its free block
  int64_t free_dofs = 0;
  int64_t hard_tets = 0;
  int64_t flat_tets = 0;  // left out (flat_tets.h)
  int64_t factor_nonzeros = 0;
};

class FemModel {
 public:
  // mesh: #V vertices (mm) and #T positively oriented tets;
  // box_extent_mm: 3, the image box [0, extent] (mm).
  // Fails: InvalidArgument (bad material, extent, tets), FailedPrecondition
  // (nothing can move, or a rigid motion is left free).
  static Result<FemModel> Create(const ProxyMesh& mesh, const glm::dvec3& box_extent_mm,
                                 const FemOptions& options = {});

  // Takes the handles for point_mm (3, mm) and radius_mm (> 0) among the
  // current positions (FindHandles: deformable vertices that share no tet
  // with a fixed one inside the radius, and the nearest deformable vertex);
  // replaces any earlier grab and keeps the
  // current deformation, to which later drags are relative.
  Result<GrabInfo> Grab(const glm::dvec3& point_mm, double radius_mm);
  // Takes `vertices` (indices; those that are not deformable are skipped) as
  // the handles, e.g. the organ under the grab point (server/scene); info's
  // handles are replaced by the ones taken. FailedPrecondition when none is
  // deformable, InvalidArgument on a bad index.
  Result<GrabInfo> GrabVertices(const std::vector<int32_t>& vertices, GrabInfo info);

  // Moves the handles to (their displacement at grab time) + offset_mm (3,
  // mm), each along its free directions only (a handle on a box face keeps
  // sliding on it), and solves. FailedPrecondition before a Grab.
  Result<SolveStats> Drag(const glm::dvec3& offset_mm);

  // Frees the handles and applies force_n (3, N) in total, force_n / #handles
  // on each, and solves. FailedPrecondition before a Grab.
  Result<SolveStats> Pull(const glm::dvec3& force_n);

  // Solves the last Drag or Pull again: with a per-event bound
  // (SolverOptions::event_newton_budget) it goes on where that solve
  // stopped (the rest of the motion, then convergence). FailedPrecondition
  // before a Grab; with no Drag or Pull since the Grab, a Drag by 0.
  Result<SolveStats> Settle();
  // The last Drag, Pull or Settle reached its target and converged (true
  // after a Grab or Release).
  bool settled() const { return settled_; }

  // Drops the handles. keep = false: back to rest (every displacement
  // exactly 0) when nothing is held, else the tissue relaxes to what the
  // held springs hold (Settle goes on). keep = true (kSpring only): the
  // handles stay held where the drag put them (kept drags compose).
  Status Release(bool keep = false);
  // Holds `vertices` (deformable ones; others skipped) where they are now by
  // held springs (kSpring only): tissue there stays while another point is
  // pulled. FailedPrecondition with prescribed handles or no deformable vertex.
  Status Pin(const std::vector<int32_t>& vertices);
  // Back to rest: drops the handles, kept drags and pins.
  void Reset();
  int64_t held_vertices() const;
  // kSpring: the largest distance of a handle from its target after the last
  // solve (mm): how far the grabbed tissue lags the pointer; 0 otherwise.
  double lag_mm() const { return lag_mm_; }

  bool grabbed() const { return grabbed_; }
  const GrabInfo& grab() const { return grab_; }
  int64_t vertex_count() const { return static_cast<int64_t>(rest_mm_.size()); }
  const std::vector<glm::dvec3>& rest_positions_mm() const { return rest_mm_; }
  // The tets the FEM uses: the mesh's, flat ones left out.
  const std::vector<std::array<int32_t, 4>>& tets() const { return tets_; }
  // #V by 3: current positions and displacements, mm.
  std::vector<glm::dvec3> Positions() const;
  std::vector<glm::dvec3> Displacements() const;
  // The largest vertex displacement, mm.
  double MaxDisplacementMm() const;
  // tets() with signed volume <= 0 at the current positions (section 6
  // validity).
  int64_t CountInvertedTets() const;
  // #V flags: may be a handle.
  const std::vector<uint8_t>& deformable() const { return deformable_; }
  // #V lists: the fully fixed vertices (skeleton, anchors) sharing a tet with
  // each vertex, ascending.
  const std::vector<std::vector<int32_t>>& fixed_neighbours() const { return fixed_neighbours_; }
  const FemSetupStats& setup() const { return setup_; }
  const CorotationalSolver& solver() const { return solver_; }

 private:
  FemModel() = default;
  Status CheckGrabbed(const char* action) const;
  // kSpring: gives the solver the springs of the handles (when `active`) and
  // the held DOFs, refactoring when the set changed; fills target_mm (3*#V).
  Status ApplySprings(bool active, const glm::dvec3& offset_mm, Eigen::VectorXd& target_mm);
  Result<SolveStats> SolveHeld();  // kSpring with no handles: towards the held targets
  // Records whether `stats` (a Drag or Pull) reached and converged; passes it on.
  Result<SolveStats> Settled(Result<SolveStats> stats);

  std::vector<glm::dvec3> rest_mm_;
  std::vector<std::array<int32_t, 4>> tets_;
  glm::dvec3 box_extent_mm_{0.0};
  std::vector<uint8_t> deformable_;
  std::vector<std::vector<int32_t>> fixed_neighbours_;  // #V: fully fixed vertices sharing a tet
  CorotationalSolver solver_;
  FemSetupStats setup_;
  bool grabbed_ = false;
  GrabInfo grab_;
  std::vector<int32_t> handle_dofs_;      // free DOFs of the handles
  Eigen::VectorXd displacement_at_grab_;  // 3*#V, mm
  // The last load (Settle repeats it) and whether it was reached.
  bool last_was_pull_ = false;
  glm::dvec3 last_load_{0.0};  // drag offset, mm, or pull force, N
  bool settled_ = true;
  HandleAttachment attachment_ = HandleAttachment::kPrescribed;
  double spring_factor_ = 100.0;
  std::vector<uint8_t> held_;   // 3*#V: DOF held by a kept drag or a pin
  Eigen::VectorXd held_target_;  // 3*#V, mm, where held_
  std::vector<int32_t> spring_dofs_;  // the springs the solver has now
  double lag_mm_ = 0.0;
};

}  // namespace vpm

#include "server/fem/fem_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "server/common/clock.h"
#include "server/common/finite_vec3.h"
#include "server/fem/fixed_dofs.h"
#include "server/fem/flat_tets.h"
#include "server/mesh/tet_quality.h"

namespace vpm {
namespace {

// #V lists: the vertices whose every DOF is fixed that share a tet with
// the vertex, ascending.
std::vector<std::vector<int32_t>> FixedNeighbours(const std::vector<std::array<int32_t, 4>>& tets,
                                                  const std::vector<uint8_t>& fixed_dofs) {
  const auto all_fixed = [&](int32_t v) {
    return fixed_dofs[3 * v] && fixed_dofs[3 * v + 1] && fixed_dofs[3 * v + 2];
  };
  std::vector<std::vector<int32_t>> out(fixed_dofs.size() / 3);
  for (const auto& tet : tets) {
    for (int32_t f : tet) {
      if (!all_fixed(f)) continue;
      for (int32_t v : tet) {
        if (v != f) out[v].push_back(f);
      }
    }
  }
  for (auto& list : out) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return out;
}

}  // namespace

Result<FemModel> FemModel::Create(const ProxyMesh& mesh, const glm::dvec3& box_extent_mm,
                                  const FemOptions& options) {
  ASSIGN_OR_RETURN(std::vector<uint8_t> fixed, FixedDofs(mesh, box_extent_mm));
  ASSIGN_OR_RETURN(const std::vector<double> all_young, TetYoungModuli(mesh, options.material));
  FemModel model;
  model.box_extent_mm_ = box_extent_mm;
  for (const MeshVertex& v : mesh.vertices) model.rest_mm_.push_back(v.position_mm);
  std::vector<double> young;
  for (int32_t t : NonFlatTets(model.rest_mm_, mesh.tets)) {
    model.tets_.push_back(mesh.tets[t]);
    young.push_back(all_young[t]);
  }
  model.setup_.flat_tets = static_cast<int64_t>(mesh.tets.size() - model.tets_.size());
  // A vertex in no (non-flat) tet has no stiffness: it stays where it is.
  std::vector<uint8_t> used(mesh.vertices.size(), 0);
  for (const auto& tet : model.tets_) {
    for (int32_t v : tet) used[v] = 1;
  }
  for (size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) fixed[3 * v] = fixed[3 * v + 1] = fixed[3 * v + 2] = 1;
  }
  if (!std::isfinite(options.spring_factor) || !(options.spring_factor > 0.0)) {
    return absl::InvalidArgumentError(
        StrCat("spring_factor must be finite and > 0, got ", options.spring_factor));
  }
  model.attachment_ = options.attachment;
  model.spring_factor_ = options.spring_factor;
  model.held_.assign(3 * mesh.vertices.size(), 0);
  model.held_target_.setZero(3 * static_cast<int64_t>(mesh.vertices.size()));
  ASSIGN_OR_RETURN(model.solver_,
                   CorotationalSolver::Create(model.rest_mm_, model.tets_, young,
                                              options.material.poisson, fixed, options.solver));
  model.deformable_.assign(mesh.vertices.size(), 0);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const bool any_free = !fixed[3 * v] || !fixed[3 * v + 1] || !fixed[3 * v + 2];
    model.deformable_[v] =
        !mesh.vertices[v].skeleton && mesh.vertices[v].kind != VertexKind::kAnchor && any_free;
  }
  model.fixed_neighbours_ = FixedNeighbours(model.tets_, fixed);
  const double soft = young.empty() ? 0.0 : *std::min_element(young.begin(), young.end());
  for (double e : young) model.setup_.hard_tets += e > soft;
  model.setup_.assembly_ms = model.solver_.setup_assembly_ms();
  model.setup_.factor_ms = model.solver_.setup_factor_ms();
  model.setup_.free_dofs = model.solver_.factor().free_count();
  model.setup_.factor_nonzeros = model.solver_.factor().factor_nonzeros();
  return model;
}

Result<GrabInfo> FemModel::Grab(const glm::dvec3& point_mm, double radius_mm) {
  ASSIGN_OR_RETURN(GrabInfo info, FindHandles(Positions(), deformable_, fixed_neighbours_,
                                              box_extent_mm_, point_mm, radius_mm));
  const std::vector<int32_t> handles = info.handles;
  return GrabVertices(handles, std::move(info));
}

Result<GrabInfo> FemModel::GrabVertices(const std::vector<int32_t>& vertices, GrabInfo info) {
  std::vector<int32_t> handles;
  for (int32_t v : vertices) {
    if (v < 0 || v >= vertex_count()) {
      return absl::InvalidArgumentError(StrCat("grab: vertex ", v, " does not exist"));
    }
    if (deformable_[v]) handles.push_back(v);
  }
  std::sort(handles.begin(), handles.end());
  handles.erase(std::unique(handles.begin(), handles.end()), handles.end());
  if (handles.empty()) {
    return absl::FailedPreconditionError(
        StrCat("none of the ", vertices.size(), " vertices to grab can move (skeleton or corners)"));
  }
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<int32_t> dofs;
  for (int32_t v : handles) {
    for (int i = 0; i < 3; ++i) {
      if (!solver_.fixed_dofs()[3 * v + i]) dofs.push_back(3 * v + i);
    }
  }
  handle_dofs_ = std::move(dofs);
  displacement_at_grab_ = solver_.displacement_mm();
  if (attachment_ == HandleAttachment::kPrescribed) {
    RETURN_IF_ERROR(solver_.SetHandles(handle_dofs_));
  } else {
    Eigen::VectorXd target;
    RETURN_IF_ERROR(ApplySprings(true, glm::dvec3(0.0), target));
  }
  info.handles = std::move(handles);
  info.setup_ms = MsSince(t0);
  grab_ = info;
  grabbed_ = true;
  last_was_pull_ = false;
  last_load_ = glm::dvec3(0.0);
  settled_ = true;
  lag_mm_ = 0.0;
  return info;
}

Status FemModel::ApplySprings(bool active, const glm::dvec3& offset_mm,
                              Eigen::VectorXd& target_mm) {
  target_mm = held_target_;
  std::vector<uint8_t> sprung = held_;
  if (active) {
    for (int32_t d : handle_dofs_) {
      target_mm[d] = displacement_at_grab_[d] + offset_mm[d % 3];
      sprung[d] = 1;
    }
  }
  std::vector<int32_t> dofs;
  for (size_t d = 0; d < sprung.size(); ++d) {
    if (sprung[d]) dofs.push_back(static_cast<int32_t>(d));
  }
  if (dofs == spring_dofs_ && !spring_dofs_.empty()) return absl::OkStatus();
  std::vector<double> stiffness(dofs.size());
  for (size_t j = 0; j < dofs.size(); ++j) {
    stiffness[j] = spring_factor_ * solver_.rest_diagonal()[dofs[j]];
  }
  RETURN_IF_ERROR(solver_.SetHandleSprings(dofs, stiffness));
  spring_dofs_ = std::move(dofs);
  return absl::OkStatus();
}

Status FemModel::CheckGrabbed(const char* action) const {
  if (!grabbed_) {
    return absl::FailedPreconditionError(StrCat(action, " needs a grab first (no handles held)"));
  }
  return absl::OkStatus();
}

Result<SolveStats> FemModel::Drag(const glm::dvec3& offset_mm) {
  RETURN_IF_ERROR(CheckGrabbed("drag"));
  if (!IsFinite(offset_mm)) return absl::InvalidArgumentError("drag offset must be finite");
  last_was_pull_ = false;
  last_load_ = offset_mm;
  if (attachment_ == HandleAttachment::kSpring) {
    Eigen::VectorXd target;
    RETURN_IF_ERROR(ApplySprings(true, offset_mm, target));
    Result<SolveStats> stats =
        solver_.Solve(target, Eigen::VectorXd::Zero(target.size()), HandleMode::kSpring);
    lag_mm_ = 0.0;
    if (stats.ok()) {
      for (int32_t v : grab_.handles) {
        // Fixed DOFs (a handle on a box face) cannot follow: not lag.
        glm::dvec3 gap(0.0);
        for (int i = 0; i < 3; ++i) {
          const int32_t d = 3 * v + i;
          if (!solver_.fixed_dofs()[d]) gap[i] = target[d] - solver_.displacement_mm()[d];
        }
        lag_mm_ = std::max(lag_mm_, glm::length(gap));
      }
    }
    return Settled(std::move(stats));
  }
  // Fixed DOFs are 0 in every state, so the grab-time state prescribes them.
  Eigen::VectorXd prescribed = displacement_at_grab_;
  for (int32_t d : handle_dofs_) prescribed[d] = displacement_at_grab_[d] + offset_mm[d % 3];
  last_was_pull_ = false;
  last_load_ = offset_mm;
  return Settled(solver_.Solve(prescribed, Eigen::VectorXd::Zero(prescribed.size()),
                               HandleMode::kPrescribed));
}

Result<SolveStats> FemModel::Settle() {
  if (!grabbed_ && attachment_ == HandleAttachment::kSpring && held_vertices() > 0) {
    return SolveHeld();
  }
  RETURN_IF_ERROR(CheckGrabbed("settle"));
  return last_was_pull_ ? Pull(last_load_) : Drag(last_load_);
}

Result<SolveStats> FemModel::Settled(Result<SolveStats> stats) {
  settled_ = stats.ok() && stats->converged && stats->target_fraction == 1.0;
  if (stats.ok() && attachment_ == HandleAttachment::kSpring) stats->spring_lag_mm = lag_mm_;
  return stats;
}

Result<SolveStats> FemModel::Pull(const glm::dvec3& force_n) {
  RETURN_IF_ERROR(CheckGrabbed("pull"));
  if (!IsFinite(force_n)) return absl::InvalidArgumentError("pull force must be finite");
  const Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(3 * vertex_count());
  Eigen::VectorXd force = Eigen::VectorXd::Zero(3 * vertex_count());
  const double share = 1.0 / static_cast<double>(grab_.handles.size());
  for (int32_t v : grab_.handles) {
    for (int i = 0; i < 3; ++i) force[3 * v + i] = force_n[i] * share;
  }
  last_was_pull_ = true;
  last_load_ = force_n;
  if (attachment_ == HandleAttachment::kSpring && held_vertices() > 0) {
    Eigen::VectorXd target;
    RETURN_IF_ERROR(ApplySprings(false, glm::dvec3(0.0), target));
    return Settled(solver_.Solve(target, force, HandleMode::kSpring));
  }
  return Settled(solver_.Solve(prescribed, force, HandleMode::kFree));
}

Status FemModel::Release(bool keep) {
  if (keep) {
    if (attachment_ != HandleAttachment::kSpring) {
      return absl::FailedPreconditionError("keeping a drag needs spring handles");
    }
    RETURN_IF_ERROR(CheckGrabbed("keep"));
    // Held where the drag's targets are (a pull: where the handles are now).
    for (int32_t d : handle_dofs_) {
      held_[d] = 1;
      held_target_[d] = last_was_pull_ ? solver_.displacement_mm()[d]
                                       : displacement_at_grab_[d] + last_load_[d % 3];
    }
  }
  grabbed_ = false;
  grab_ = GrabInfo{};
  handle_dofs_.clear();
  lag_mm_ = 0.0;
  if (held_vertices() == 0) {
    Reset();
    return absl::OkStatus();
  }
  // The tissue relaxes to what the held springs hold: Settle solves it.
  settled_ = false;
  return absl::OkStatus();
}

Status FemModel::Pin(const std::vector<int32_t>& vertices) {
  if (attachment_ != HandleAttachment::kSpring) {
    return absl::FailedPreconditionError("pins need spring handles");
  }
  int64_t pinned = 0;
  for (int32_t v : vertices) {
    if (v < 0 || v >= vertex_count()) {
      return absl::InvalidArgumentError(StrCat("pin: vertex ", v, " does not exist"));
    }
    if (!deformable_[v]) continue;
    for (int i = 0; i < 3; ++i) {
      const int32_t d = 3 * v + i;
      if (solver_.fixed_dofs()[d]) continue;
      held_[d] = 1;
      held_target_[d] = solver_.displacement_mm()[d];
    }
    ++pinned;
  }
  if (pinned == 0) {
    return absl::FailedPreconditionError("no deformable vertex to pin there (skeleton or corners)");
  }
  return absl::OkStatus();
}

Result<SolveStats> FemModel::SolveHeld() {
  Eigen::VectorXd target;
  RETURN_IF_ERROR(ApplySprings(false, glm::dvec3(0.0), target));
  Result<SolveStats> stats =
      solver_.Solve(target, Eigen::VectorXd::Zero(target.size()), HandleMode::kSpring);
  settled_ = stats.ok() && stats->converged;
  return stats;
}

void FemModel::Reset() {
  solver_.Reset();
  grabbed_ = false;
  grab_ = GrabInfo{};
  handle_dofs_.clear();
  displacement_at_grab_.setZero(3 * vertex_count());
  std::fill(held_.begin(), held_.end(), 0);
  held_target_.setZero();
  settled_ = true;
  lag_mm_ = 0.0;
  spring_dofs_.clear();
  // The handles' capacitance is dropped too; clearing cannot fail.
  (void)solver_.SetHandles({});
}

int64_t FemModel::held_vertices() const {
  int64_t count = 0;
  for (size_t v = 0; 3 * v < held_.size(); ++v) {
    count += held_[3 * v] || held_[3 * v + 1] || held_[3 * v + 2];
  }
  return count;
}

std::vector<glm::dvec3> FemModel::Displacements() const {
  const Eigen::VectorXd& u = solver_.displacement_mm();
  std::vector<glm::dvec3> out(rest_mm_.size());
  for (size_t v = 0; v < out.size(); ++v) out[v] = glm::dvec3(u[3 * v], u[3 * v + 1], u[3 * v + 2]);
  return out;
}

double FemModel::MaxDisplacementMm() const {
  const Eigen::VectorXd& u = solver_.displacement_mm();
  double max_sq = 0.0;
  for (Eigen::Index v = 0; v + 2 < u.size(); v += 3) {
    max_sq = std::max(max_sq, u[v] * u[v] + u[v + 1] * u[v + 1] + u[v + 2] * u[v + 2]);
  }
  return std::sqrt(max_sq);
}

std::vector<glm::dvec3> FemModel::Positions() const {
  std::vector<glm::dvec3> out = Displacements();
  for (size_t v = 0; v < out.size(); ++v) out[v] += rest_mm_[v];
  return out;
}

int64_t FemModel::CountInvertedTets() const { return vpm::CountInvertedTets(Positions(), tets_); }

}  // namespace vpm

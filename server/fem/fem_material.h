// Material per tet (docs/ALGORITHM.md section 5): soft tissue everywhere, hard
// (bone) in every tet that touches a hard vertex.
#pragma once

#include <vector>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

struct FemMaterial {
  double young_soft_kpa = 5.0;  // E_soft, kPa, > 0
  double poisson = 0.45;        // nu, dimensionless, in (-1, 0.5)
  double hard_factor = 1e4;     // E_hard = hard_factor * E_soft, >= 1
};

// InvalidArgument naming the field when a value is out of its range or not
// finite.
Status ValidateMaterial(const FemMaterial& material);

// Lame parameters of an isotropic material, same unit as `young`:
//   lambda = E nu / ((1 + nu)(1 - 2 nu)),  mu = E / (2 (1 + nu)).
struct LameParameters {
  double lambda = 0.0;
  double mu = 0.0;
};
LameParameters Lame(double young, double poisson);

// Young's modulus of every tet.
//   mesh     vertices (hard flags) and #T tets
// Output: #T moduli, N/mm^2: E_hard for a tet with at least one hard vertex,
// E_soft otherwise. Fails on an invalid material or a vertex index out of
// range.
Result<std::vector<double>> TetYoungModuli(const ProxyMesh& mesh, const FemMaterial& material);

}  // namespace vpm

// The global stiffness matrix as a sparse matrix (for the factorisation and
// for tests; the solver's iterations apply it matrix-free).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "server/fem/corotated_forces.h"
#include "server/fem/tet_element.h"

namespace vpm {

// K = sum_e K_e with K_e the tangent of ApplyElementTangent.
//   elements      #T
//   frames        #T rotations (and optional twist matrices) from
//                 CorotatedForces; frames.rotations empty: the rest
//                 stiffness sum_e K0_e
//   vertex_count  #V
// Output: 3*#V by 3*#V, N/mm, symmetric, both triangles stored, compressed.
Eigen::SparseMatrix<double> AssembleStiffness(const std::vector<TetElement>& elements,
                                              const CorotatedFrames& frames, int64_t vertex_count);

}  // namespace vpm

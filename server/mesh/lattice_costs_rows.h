// Step 1 (docs/ALGORITHM.md section 1) in native code, a voxel row at a
// time: the same four costs as EvaluateLatticeCostsCpu (the double-precision
// reference, one voxel and its six neighbours at a time) and the
// lattice_costs_rows.comp / lattice_costs_cells.comp kernels, for devices
// where the "GPU" is the CPU itself (lavapipe). There the kernels cost about
// 17 ns per voxel (4 s on a 512 x 512 x 900 CT) against about 1 ns here: each
// row's TF and |grad I|^2 are computed in contiguous, vectorisable loops
// (int16 volumes read TF from a table of every stored value), then reduced
// per lattice cell; threads take whole cell layers. DecimateLattice picks it
// when the lattice-cost op runs on a CPU device (docs/MESH.md).
//
// Precision: TF and the cell sums in double, |grad I|^2 in float from exact
// integer (or float) differences; against the reference within 1e-6
// relative (tests/mesh/lattice_costs_rows_test.cc).
#pragma once

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "server/volume/transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

// Both footprints for every vertex of `lattice`, on `threads` threads
// (0: the hardware's count). Every thread polls `cancel` before each cell
// layer (a 512 x 512 x 900 CT on a 60^3 lattice: a layer is about 4 ms of
// 0.24 s), and a cancelled evaluation returns the poll's status.
Result<LatticeCosts> EvaluateLatticeCostsRows(const Volume& volume, const Lattice& lattice,
                                              const TransferFunction& tf, int threads = 0,
                                              const CancelToken& cancel = {});

}  // namespace vpm

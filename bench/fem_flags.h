// Command-line flags that the FEM benchmarks share: solver settings
// (SolverOptions) and which meshes to run.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "server/fem/corotational_solver.h"

namespace vpm::bench {

struct FemFlags {
  SolverOptions solver;
  int64_t max_vertices = int64_t{1} << 30;  // only meshes decimated to at most this
};

// Reads the flag at argv[i] (and its value, advancing i) when it is one of
//   --max-load-steps N  --min-load-fraction F  --intermediate-newton N
//   --max-vertices N  --handle-factor refactor|capacitance
//   --event-newton-budget N (0: unbounded)  --event-stop-newton N
//   --event-max-lag SHARES (0: no limit)  --threads N (SolverOptions::threads)
// into `flags`; false for any other argument.
inline bool ParseFemFlag(int argc, char** argv, int& i, FemFlags& flags) {
  if (i + 1 >= argc) return false;
  if (std::strcmp(argv[i], "--max-load-steps") == 0) {
    flags.solver.max_load_steps = std::atoi(argv[++i]);
  } else if (std::strcmp(argv[i], "--min-load-fraction") == 0) {
    flags.solver.min_load_fraction = std::atof(argv[++i]);
  } else if (std::strcmp(argv[i], "--intermediate-newton") == 0) {
    flags.solver.intermediate_newton_iterations = std::atoi(argv[++i]);
  } else if (std::strcmp(argv[i], "--handle-factor") == 0) {
    flags.solver.handle_factor = std::strcmp(argv[++i], "capacitance") == 0
                                     ? HandleFactor::kCapacitance
                                     : HandleFactor::kRefactor;
  } else if (std::strcmp(argv[i], "--event-newton-budget") == 0) {
    flags.solver.event_newton_budget = std::atoi(argv[++i]);
  } else if (std::strcmp(argv[i], "--event-stop-newton") == 0) {
    flags.solver.event_stop_newton_iterations = std::atoi(argv[++i]);
  } else if (std::strcmp(argv[i], "--event-max-lag") == 0) {
    flags.solver.event_max_lag_shares = std::atof(argv[++i]);
  } else if (std::strcmp(argv[i], "--threads") == 0) {
    flags.solver.threads = std::atoi(argv[++i]);
  } else if (std::strcmp(argv[i], "--max-vertices") == 0) {
    flags.max_vertices = std::atoll(argv[++i]);
  } else {
    return false;
  }
  return true;
}

}  // namespace vpm::bench

// Units inside the FEM (docs/ALGORITHM.md section 5).
//
// The API takes Young's modulus in kPa (the unit of soft-tissue elastography)
// and everything else in the project's units. Internally one consistent set
// is used, so that no conversion happens in the inner loops:
//   length        mm
//   force         N
//   stress, E     N/mm^2 (= MPa); 1 kPa = 1e-3 N/mm^2
//   stiffness     N/mm (entries of K)
//   energy        N*mm (= mJ)
// Poisson's ratio and strains are dimensionless.
#pragma once

namespace vpm {

// N/mm^2 per kPa.
inline constexpr double kNPerMm2PerKpa = 1e-3;

inline constexpr double KpaToNPerMm2(double kpa) { return kpa * kNPerMm2PerKpa; }
inline constexpr double NPerMm2ToKpa(double n_per_mm2) { return n_per_mm2 / kNPerMm2PerKpa; }

}  // namespace vpm

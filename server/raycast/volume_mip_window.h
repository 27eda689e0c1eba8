// The default MIP window of a volume, from its own values: what a MIP shows
// before the user sets a window (`--window W L`, RenderSettings.mip_window).
//
// Black at the 1st percentile, white at the 99.5th, of the voxels above air
// when the volume is CT in HU (it holds values below kCtAirCeilingHu: air,
// -1000 HU, and lungs, about -850 HU, are left out, so that the window spans
// the body's tissue from fat to bone), else of all voxels (MRI). Counted
// on at most 2^20 voxels taken at a regular stride.
#pragma once

#include "server/raycast/render_presets.h"
#include "server/volume/volume.h"

namespace vpm {

inline constexpr double kCtAirCeilingHu = -500.0;
inline constexpr double kMipWindowLowPercentile = 1.0;
inline constexpr double kMipWindowHighPercentile = 99.5;

// True for a volume that holds air in HU (a value below kCtAirCeilingHu).
bool IsCtInHu(const Volume& volume);

// Level and width > 0 (at least 1e-3, so that a flat volume still gives a
// valid window).
MipWindow VolumeMipWindow(const Volume& volume);

// The p-th percentiles (p in [0, 100], linear between ranks) of `values`,
// which it reorders; empty `values` give 0.
std::vector<double> Percentiles(std::vector<float>& values, const std::vector<double>& p);

// At most 2^20 of the volume's values above `floor`, at a regular stride.
std::vector<float> SampleVolumeValues(const Volume& volume, double floor);

}  // namespace vpm

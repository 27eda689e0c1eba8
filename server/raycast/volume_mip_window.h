// The default MIP window of a volume, from its own values: what a MIP shows
// before the user sets a window (`--window W L`, RenderSettings.mip_window).
//
// Black at the 1st percentile, white at the 99.5th, of the voxels above air
// when the volume is CT in HU (IsCtInHu, server/volume/ct_in_hu.h: values
// below kCtAirCeilingHu, air at -1000 HU and lungs at about -850 HU, are
// left out, so that the window spans the body's tissue from fat to bone),
// else of all voxels (MRI). Counted on at most 2^20 voxels taken at a
// regular stride.
#pragma once

#include "server/raycast/render_presets.h"
#include "server/volume/ct_in_hu.h"
#include "server/volume/volume.h"

namespace vpm {

inline constexpr double kMipWindowLowPercentile = 1.0;
inline constexpr double kMipWindowHighPercentile = 99.5;

// Level and width > 0 (at least 1e-3, so that a flat volume still gives a
// valid window).
MipWindow VolumeMipWindow(const Volume& volume);

// The p-th percentiles (p in [0, 100], linear between ranks) of `values`,
// which it reorders; empty `values` give 0.
std::vector<double> Percentiles(std::vector<float>& values, const std::vector<double>& p);

// At most 2^20 of the volume's values above `floor`, at a regular stride.
std::vector<float> SampleVolumeValues(const Volume& volume, double floor);

}  // namespace vpm

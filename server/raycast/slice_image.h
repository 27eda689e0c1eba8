// A slice's values (SliceSampler, SampleSliceCpu) as a picture: grey levels
// through a window, the proxy mesh's tets cut by the plane drawn as their
// cut outlines, and the grab point marked.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/raycast/render_presets.h"
#include "server/raycast/slice_grid.h"
#include "server/volume/volume.h"

namespace vpm {

// A slice's window is a MipWindow (render_presets.h): values level -
// width / 2 .. level + width / 2 map to black .. white (ValidateMipWindow).
// Default: for CT in HU (IsCtInHu, server/volume/ct_in_hu.h) the
// soft-tissue window W 400 L 40 a radiologist starts from; anything else
// (MRI, unitless): the 1st to 99th percentile of the voxels
// (SampleVolumeValues, Percentiles).
MipWindow DefaultSliceWindow(const Volume& volume);

// RGBA8, width * height * 4 bytes, row 0 at the top; NaN (outside the
// volume) is black.
std::vector<uint8_t> SliceToRgba(std::span<const float> values, int width, int height,
                                 const MipWindow& window);

// Where each deformed tet (positions_mm #V by 3, physical mm; tets #T by 4)
// meets the plane: the segments its faces cut, drawn 1 pixel wide in `rgb`.
// Returns how many tets the plane cuts.
int64_t DrawCutTets(const SliceGrid& grid, std::span<const glm::dvec3> positions_mm,
                    std::span<const std::array<int32_t, 4>> tets, const uint8_t rgb[3],
                    std::span<uint8_t> rgba);

// A cross at `point_mm` (physical) when it lies within `within_mm` of the
// plane; false when it does not (nothing drawn).
bool DrawSliceMarker(const SliceGrid& grid, const glm::dvec3& point_mm, double within_mm,
                     const uint8_t rgb[3], std::span<uint8_t> rgba);

}  // namespace vpm

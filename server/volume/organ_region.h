// The tissue connected to a point: the organ a grab takes (docs/FEM.md,
// "The organ grab"). Region growing from the seed's cell through cells of
// similar intensity, within a bound, then a morphological opening that cuts
// thin bridges into neighbouring tissue of the same intensity (a kidney
// touching the psoas or the liver at one or two cells).
//
// Cells are taken while |I - reference| <= window, with the reference the
// dominant intensity of the seed's 5 x 5 x 5 cells (the value with most
// neighbours within half the window, so a click beside a hilum or on a
// partial-volume cell finds the organ) and the window window_fraction x the
// volume's robust range (2nd to 98th percentile of a sample of its voxels):
// on the abdominal CT of tests/data about +-36 HU, so parenchyma is taken
// and the fat around it (-100 HU) is not; an MRI gets the same fraction of
// its own range. A window from the seed's local spread was tried and
// dropped: next to an organ's hilum the spread is the fat's, and the region
// flooded the abdomen.
//
// The cells are those of a working grid of about 3 mm (kOrganWorkingSpacingMm):
// finer voxels are averaged in blocks first, so that the opening's one cell
// cuts contacts of a few millimetres and the window sees tissue, not the
// noise of fine voxels, whatever the scanner's voxel size. The handles it
// chooses are mesh vertices some 10-20 mm apart, which a 3 mm region
// places as well as a finer one.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/block_average.h"
#include "server/volume/volume.h"

namespace vpm {

// The organ region's working grid cell, mm: the size of the voxels the
// window and the opening were set on (the abdominal CT of tests/data, 3 mm).
inline constexpr double kOrganWorkingSpacingMm = 3.0;

struct OrganRegionParams {
  double max_radius_mm = 80.0;   // no voxel of the region farther from the seed, mm
  double window_fraction = 0.03;  // of the robust intensity range
  int opening_voxels = 1;         // erosion then dilation, face-connected steps of the grid
  // The working grid's cell, mm: the region is grown on the volume's voxels
  // merged into blocks of floor(working_spacing_mm / spacing) per axis (at
  // least 1), each block's mean; 0: on the voxels themselves.
  double working_spacing_mm = kOrganWorkingSpacingMm;
};

struct OrganRegion {
  BlockGrid grid;               // the working grid (whole volume, factor 1, when not merged)
  std::vector<int64_t> voxels;  // the region's cells, linear on `grid` (i fastest), ascending
  float reference = 0.0f;       // the organ's intensity around the seed (on the grid)
  float window = 0.0f;          // accepted |I - reference|, the volume's units
  double volume_mm3 = 0.0;
  bool reached_bound = false;   // some voxel at max_radius_mm: the organ goes on
  bool lenient_opening = false;  // noise broke the strict opening's core (organ_region.cc)
  // Whether voxel (i, j, k) of the volume lies in a cell of the region.
  bool Contains(int64_t i, int64_t j, int64_t k) const;
};

// seed_mm: physical voxel space, mm. InvalidArgument for a non-finite seed
// or bad params; OutOfRange for a seed outside the volume. A seed whose own
// voxel falls outside the window (noise) gives a region of that voxel only.
Result<OrganRegion> GrowOrganRegion(const Volume& volume, const glm::dvec3& seed_mm,
                                    const OrganRegionParams& params = {});

}  // namespace vpm

// The tissue connected to a point: the organ a grab takes (docs/FEM.md,
// "The organ grab"). Region growing from the seed voxel through voxels of
// similar intensity, within a bound, then a morphological opening that cuts
// thin bridges into neighbouring tissue of the same intensity (a kidney
// touching the psoas or the liver at one or two voxels).
//
// Voxels are taken while |I - reference| <= window, with the reference the
// dominant intensity of the seed's 5 x 5 x 5 voxels (the value with most
// neighbours within half the window, so a click beside a hilum or on a
// partial-volume voxel finds the organ) and the window window_fraction x the
// volume's robust range (2nd to 98th percentile of a sample of its voxels):
// on the abdominal CT of tests/data about +-36 HU, so parenchyma is taken
// and the fat around it (-100 HU) is not; an MRI gets the same fraction of
// its own range. A window from the seed's local spread was tried and
// dropped: next to an organ's hilum the spread is the fat's, and the region
// flooded the abdomen.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

struct OrganRegionParams {
  double max_radius_mm = 80.0;   // no voxel of the region farther from the seed, mm
  double window_fraction = 0.03;  // of the robust intensity range
  int opening_voxels = 1;        // erosion then dilation, face-connected steps
};

struct OrganRegion {
  std::vector<int64_t> voxels;  // linear indices (Volume::LinearIndex), ascending
  float reference = 0.0f;       // the organ's intensity around the seed
  float window = 0.0f;          // accepted |I - reference|, the volume's units
  double volume_mm3 = 0.0;
  bool reached_bound = false;   // some voxel at max_radius_mm: the organ goes on
  bool Contains(int64_t linear) const;
};

// seed_mm: physical voxel space, mm. InvalidArgument for a non-finite seed
// or bad params; OutOfRange for a seed outside the volume. A seed whose own
// voxel falls outside the window (noise) gives a region of that voxel only.
Result<OrganRegion> GrowOrganRegion(const Volume& volume, const glm::dvec3& seed_mm,
                                    const OrganRegionParams& params = {});

}  // namespace vpm

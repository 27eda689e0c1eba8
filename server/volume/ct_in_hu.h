// Whether a volume is CT in Hounsfield units: what decides if vpm's HU rules
// apply (bone marked hard, the CT transfer cost and render preset; docs/
// MESH.md, "Step 3: classification"). An MRI's intensities say nothing of
// bone: bright fat would be fixed as skeleton.
//
// A volume read from DICOM is CT when its Modality (0008,0060) is CT (the
// reader applies the rescale, so its values are HU) and not CT for any other
// modality. Other sources (NIfTI, NRRD, MetaImage, raw, phantoms) carry no
// modality: CT in HU when they hold air, a value below kCtAirCeilingHu
// (-1000 HU outside the body, or a scanner's padding of -1024 to -3024);
// magnitude MRI is never negative.
#pragma once

#include "server/volume/volume.h"

namespace vpm {

inline constexpr double kCtAirCeilingHu = -500.0;

bool IsCtInHu(const Volume& volume);

}  // namespace vpm

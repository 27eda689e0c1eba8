#include "server/volume/ct_in_hu.h"

#include <string>

#include "server/volume/dicom_origin.h"

namespace vpm {

bool IsCtInHu(const Volume& volume) {
  if (volume.dicom_origin() != nullptr) {
    const std::string modality = volume.dicom_origin()->Get(kDicomModalityTag);
    if (!modality.empty()) return modality == "CT";
  }
  return volume.min_value() < kCtAirCeilingHu;
}

}  // namespace vpm

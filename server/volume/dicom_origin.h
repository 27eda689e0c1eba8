// What a volume read from a DICOM series keeps of it, so that a derived
// series can be written back into the same study (server/io/
// write_derived_series.h): the patient, study, frame-of-reference and
// acquisition attributes its slices share, and the instances it was read
// from. Held in memory with the volume only; it holds patient identifiers,
// so it is never logged.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

// Modality (0008,0060), as DicomOrigin::Get takes a tag.
inline constexpr uint32_t kDicomModalityTag = 0x00080060;

struct DicomSourceInstance {
  std::string sop_class_uid;
  std::string sop_instance_uid;
  glm::dvec3 position_mm{0.0};  // ImagePositionPatient (world LPS) of its first pixel
};

struct DicomOrigin {
  // (tag as 0xGGGGEEEE, value as DCMTK prints it, multiple values joined by
  // '\'), in tag order: the attributes of the first instance that a
  // derived image copies (patient, study, frame of reference, modality,
  // character set, MR acquisition); absent attributes are not listed.
  std::vector<std::pair<uint32_t, std::string>> attributes;
  std::vector<DicomSourceInstance> instances;  // in file order

  // The value of `tag`, or "" when absent.
  std::string Get(uint32_t tag) const {
    for (const auto& [t, value] : attributes) {
      if (t == tag) return value;
    }
    return {};
  }
};

}  // namespace vpm

#include "server/io/write_derived_series.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <dcmtk/dcmdata/dctk.h>

namespace vpm {
namespace {

// Stored value = (value - intercept) / slope, in int16.
struct Rescale {
  double slope = 1.0;
  double intercept = 0.0;
};

Rescale RescaleFor(const Volume& volume) {
  const double lo = volume.min_value(), hi = volume.max_value();
  if (lo >= -32768.0 && hi <= 32767.0) return {};
  const double slope = std::max(hi - lo, 1e-30) / 65535.0;
  return {.slope = slope, .intercept = lo + 32768.0 * slope};
}

std::string DicomDecimal(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);  // DS: at most 16 characters
  return text;
}

std::string DicomTriple(const glm::dvec3& v) {
  return StrCat(DicomDecimal(v.x), "\\", DicomDecimal(v.y), "\\", DicomDecimal(v.z));
}

// The MR image module's acquisition attributes, from the source or their
// "not known" values.
Status PutMrAcquisition(DcmDataset& ds, const DicomOrigin* origin) {
  const auto have = [&](const DcmTagKey& key) {
    return origin != nullptr &&
           !origin->Get((uint32_t{key.getGroup()} << 16) | key.getElement()).empty();
  };
  if (!have(DCM_ScanningSequence)) RETURN_IF_ERROR(PutDicomString(ds, DCM_ScanningSequence, "RM"));
  if (!have(DCM_SequenceVariant)) RETURN_IF_ERROR(PutDicomString(ds, DCM_SequenceVariant, "NONE"));
  for (const DcmTagKey& key : {DCM_ScanOptions, DCM_MRAcquisitionType, DCM_EchoTime,
                               DCM_EchoTrainLength, DCM_RepetitionTime}) {
    if (!have(key)) RETURN_IF_ERROR(PutDicomString(ds, key, ""));
  }
  return absl::OkStatus();
}

// The source instance whose position is nearest `position_mm`.
const DicomSourceInstance* NearestSource(const DicomOrigin* origin, const glm::dvec3& position_mm) {
  if (origin == nullptr) return nullptr;
  const DicomSourceInstance* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const DicomSourceInstance& s : origin->instances) {
    const double d = glm::length(s.position_mm - position_mm);
    if (d < best_d && !s.sop_instance_uid.empty()) best = &s, best_d = d;
  }
  return best;
}

Status PutSourceReference(DcmDataset& ds, const DicomSourceInstance* source) {
  if (source == nullptr) return absl::OkStatus();
  DcmItem* item = nullptr;
  if (ds.findOrCreateSequenceItem(DCM_SourceImageSequence, item, 0).bad() || item == nullptr) {
    return absl::InternalError("cannot add SourceImageSequence");
  }
  item->putAndInsertString(DCM_ReferencedSOPClassUID, source->sop_class_uid.c_str());
  item->putAndInsertString(DCM_ReferencedSOPInstanceUID, source->sop_instance_uid.c_str());
  return absl::OkStatus();
}

Status PutPixels(DcmDataset& ds, const Volume& volume, int64_t k, const Rescale& rescale) {
  const int64_t nx = volume.dims()[0], ny = volume.dims()[1];
  std::vector<Uint16> stored(static_cast<size_t>(nx * ny));
  for (int64_t j = 0; j < ny; ++j) {
    for (int64_t i = 0; i < nx; ++i) {
      const double v = (volume.At(i, j, k) - rescale.intercept) / rescale.slope;
      const double clamped = std::clamp(std::round(std::isfinite(v) ? v : -32768.0), -32768.0, 32767.0);
      stored[i + nx * j] = static_cast<Uint16>(static_cast<int16_t>(clamped));
    }
  }
  PutImagePixelModule(ds, 1, ny, nx, 16, /*is_signed=*/true);
  RETURN_IF_ERROR(PutDicomString(ds, DCM_RescaleSlope, DicomDecimal(rescale.slope)));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_RescaleIntercept, DicomDecimal(rescale.intercept)));
  const OFCondition c = ds.putAndInsertUint16Array(DCM_PixelData, stored.data(),
                                                   static_cast<unsigned long>(stored.size()));
  if (c.bad()) return absl::InternalError(StrCat("cannot set PixelData: ", c.text()));
  return absl::OkStatus();
}

Status PutPlane(DcmDataset& ds, const VolumeGeometry& g, int64_t k, glm::dvec3* position_mm) {
  *position_mm = g.PhysicalToWorld(glm::dvec3(0.0, 0.0, double(k) * g.spacing_mm.z));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ImagePositionPatient, DicomTriple(*position_mm)));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ImageOrientationPatient,
                      StrCat(DicomTriple(g.direction[0]), "\\", DicomTriple(g.direction[1]))));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_PixelSpacing,
                      StrCat(DicomDecimal(g.spacing_mm.y), "\\", DicomDecimal(g.spacing_mm.x))));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SliceThickness, DicomDecimal(g.spacing_mm.z)));
  return PutDicomString(ds, DCM_SliceLocation,
             DicomDecimal(glm::dot(*position_mm, glm::normalize(glm::cross(g.direction[0],
                                                                      g.direction[1])))));
}

}  // namespace

Result<std::vector<DicomFileBytes>> WriteDerivedSeries(const Volume& volume,
                                                       const DicomOrigin* origin,
                                                       const DicomExportIds& ids,
                                                       const DerivedSeriesText& text,
                                                       const ProgressFn& progress) {
  const std::string modality = origin ? origin->Get(kDicomModalityTag) : std::string("CT");
  if (modality != "CT" && modality != "MR") {
    return absl::InvalidArgumentError(StrCat("the source series is ", modality.empty() ? "of no modality" : modality,
                                             ": a derived series is written for CT and MR sources"));
  }
  if (text.series_description.size() > 64 || text.derivation_description.size() > 1024) {
    return absl::InvalidArgumentError(
        "series description over 64 characters or derivation description over 1024");
  }
  const VolumeGeometry& g = volume.geometry();
  if (g.dims[0] > 65535 || g.dims[1] > 65535) {
    return absl::InvalidArgumentError("slices over 65535 pixels a side cannot be DICOM images");
  }
  const bool mr = modality == "MR";
  const Rescale rescale = RescaleFor(volume);
  std::vector<DicomFileBytes> files;
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    DcmFileFormat file;
    DcmDataset& ds = *file.getDataset();
    RETURN_IF_ERROR(PutCommonModules(ds, origin, ids, /*image_plane=*/true, mr ? UID_MRImageStorage : UID_CTImageStorage,
                                     modality, ids.derived_series_uid, ids.derived_series_number,
                                     text.series_description, k + 1));
    RETURN_IF_ERROR(PutDicomString(ds, DCM_ImageType, mr ? "DERIVED\\SECONDARY\\OTHER"
                                              : "DERIVED\\SECONDARY\\AXIAL"));
    RETURN_IF_ERROR(PutDicomString(ds, DCM_DerivationDescription, text.derivation_description));
    if (mr) RETURN_IF_ERROR(PutMrAcquisition(ds, origin));
    if (!mr) {
      RETURN_IF_ERROR(PutDicomString(ds, DCM_KVP, ""));
      RETURN_IF_ERROR(PutDicomString(ds, DCM_AcquisitionNumber, ""));
    }
    if (origin == nullptr || origin->Get(0x00185100).empty()) {
      RETURN_IF_ERROR(PutDicomString(ds, DCM_PatientPosition, ""));  // type 2C for CT and MR
    }
    glm::dvec3 position_mm;
    RETURN_IF_ERROR(PutPlane(ds, g, k, &position_mm));
    RETURN_IF_ERROR(PutSourceReference(ds, NearestSource(origin, position_mm)));
    RETURN_IF_ERROR(PutPixels(ds, volume, k, rescale));
    ASSIGN_OR_RETURN(std::string bytes, Part10Bytes(file));
    char name[32];
    std::snprintf(name, sizeof name, "%06lld.dcm", static_cast<long long>(k + 1));
    files.push_back({name, std::move(bytes)});
    if (progress) progress(double(k + 1) / double(g.dims[2]), "writing");
  }
  return files;
}

}  // namespace vpm

#include "server/io/write_secondary_capture.h"

#include <dcmtk/dcmdata/dctk.h>

namespace vpm {

Result<std::string> WriteSecondaryCapture(const std::vector<uint8_t>& rgba, int width, int height,
                                          const DicomOrigin* origin, const DicomExportIds& ids,
                                          const std::string& description) {
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535 ||
      rgba.size() != size_t(width) * size_t(height) * 4) {
    return absl::InvalidArgumentError(
        StrCat("a frame of ", width, "x", height, " pixels with ", rgba.size(), " bytes"));
  }
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  RETURN_IF_ERROR(PutCommonModules(ds, origin, ids, /*image_plane=*/false, UID_SecondaryCaptureImageStorage, "OT",
                                   ids.capture_series_uid, ids.derived_series_number + 1,
                                   description, 1));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ImageType, "DERIVED\\SECONDARY"));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ConversionType, "WSD"));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_PatientOrientation, ""));
  std::vector<uint8_t> rgb(size_t(width) * size_t(height) * 3);
  for (size_t p = 0; p < size_t(width) * size_t(height); ++p) {
    for (int c = 0; c < 3; ++c) rgb[p * 3 + c] = rgba[p * 4 + c];
  }
  PutImagePixelModule(ds, 3, height, width, 8, /*is_signed=*/false);
  const OFCondition c =
      ds.putAndInsertUint8Array(DCM_PixelData, rgb.data(), static_cast<unsigned long>(rgb.size()));
  if (c.bad()) return absl::InternalError(StrCat("cannot set PixelData: ", c.text()));
  return Part10Bytes(file);
}

}  // namespace vpm

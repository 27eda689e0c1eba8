#include "server/pacs/received_instance.h"

#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmdata/dctk.h>

#include <cstdlib>

#include "server/io/dicom_text.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {
namespace {

// UTF-8 (dicom_text.h), trailing padding removed.
std::string ReceivedText(DcmItem& ds, const DcmTagKey& key) {
  std::string text = DicomText(ds, key);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\0')) text.pop_back();
  return text;
}

}  // namespace

Result<ReceivedInstance> ReadReceivedInstance(const std::filesystem::path& path) {
  DcmFileFormat file;
  // Values over 4 KiB (the pixels) stay on disk: only the header is read.
  const OFCondition read = file.loadFile(path.c_str(), EXS_Unknown, EGL_noChange, 4096);
  if (read.bad()) return absl::InvalidArgumentError("the instance does not parse as DICOM");
  DcmDataset& ds = *file.getDataset();
  ConvertDicomTextToUtf8(ds);  // a modality's Latin-1 names, listed as UTF-8
  ReceivedInstance out{.study_uid = ReceivedText(ds, DCM_StudyInstanceUID),
                       .series_uid = ReceivedText(ds, DCM_SeriesInstanceUID),
                       .sop_uid = ReceivedText(ds, DCM_SOPInstanceUID),
                       .patient_name = ReceivedText(ds, DCM_PatientName),
                       .patient_id = ReceivedText(ds, DCM_PatientID),
                       .patient_birth_date = ReceivedText(ds, DCM_PatientBirthDate),
                       .study_date = ReceivedText(ds, DCM_StudyDate),
                       .study_description = ReceivedText(ds, DCM_StudyDescription),
                       .accession_number = ReceivedText(ds, DCM_AccessionNumber),
                       .modality = ReceivedText(ds, DCM_Modality),
                       .series_description = ReceivedText(ds, DCM_SeriesDescription),
                       .body_part = ReceivedText(ds, DCM_BodyPartExamined)};
  const std::string number = ReceivedText(ds, DCM_SeriesNumber);
  out.series_number = number.empty() ? 0 : std::atoll(number.c_str());
  RETURN_IF_ERROR(CheckUid(out.study_uid, "StudyInstanceUID"));
  RETURN_IF_ERROR(CheckUid(out.series_uid, "SeriesInstanceUID"));
  RETURN_IF_ERROR(CheckUid(out.sop_uid, "SOPInstanceUID"));
  Uint16 rows = 0, columns = 0;
  const bool pixels = ds.tagExists(DCM_PixelData) || ds.tagExists(DCM_FloatPixelData) ||
                      ds.tagExists(DCM_DoubleFloatPixelData);
  out.has_image = pixels && ds.findAndGetUint16(DCM_Rows, rows).good() &&
                  ds.findAndGetUint16(DCM_Columns, columns).good() && rows > 0 && columns > 0;
  return out;
}

}  // namespace vpm::pacs

// A deformed volume as a derived DICOM series in its source's study: one
// CT (or MR) image per slice of the volume's grid, written with DCMTK.
#pragma once

#include <string>
#include <vector>

#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/io/dicom_export_common.h"
#include "server/volume/volume.h"

namespace vpm {

struct DicomFileBytes {
  std::string name;   // "000001.dcm", ...
  std::string bytes;  // a whole Part 10 file
};

struct DerivedSeriesText {
  std::string series_description;      // SeriesDescription, at most 64 characters
  std::string derivation_description;  // DerivationDescription, at most 1024
};

// The slices of `volume` (the deformed volume, on its source's grid) as
// images of the series ids.derived_series_uid, patient and study from
// `origin` (null: a source that is not DICOM; the study is then new and the
// patient attributes empty). SOP class: MR Image Storage when the source is
// MR, else CT Image Storage. Per slice k: ImagePositionPatient = origin +
// direction * (0, 0, k * spacing_z) (world LPS mm), ImageOrientationPatient
// = the direction's first two columns, PixelSpacing = (spacing_y,
// spacing_x), SliceThickness = spacing_z; ImageType DERIVED\SECONDARY;
// signed 16-bit stored values with RescaleSlope/Intercept that hold the
// volume's range (slope 1 when it fits int16); SourceImageSequence names
// the source instance nearest to the slice. Errors: InvalidArgument for a
// source modality other than CT or MR, or descriptions over their length;
// Internal when DCMTK cannot encode. `progress` goes 0..1 by slices.
Result<std::vector<DicomFileBytes>> WriteDerivedSeries(const Volume& volume,
                                                       const DicomOrigin* origin,
                                                       const DicomExportIds& ids,
                                                       const DerivedSeriesText& text,
                                                       const ProgressFn& progress = {});

}  // namespace vpm

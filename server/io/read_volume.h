// One entry point from a source string to a Volume.
#pragma once

#include <string_view>

#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// The source forms ReadVolume accepts, for messages and help texts.
inline constexpr std::string_view kVolumeSourceForms =
    "phantom:SPEC (e.g. phantom:abdomen?size=128), a folder of DICOM files "
    "(FOLDER[?series=UID|N][&spacing=MM]), "
    "FILE.nii, FILE.nii.gz, FILE.nrrd, FILE.nhdr, FILE.mha, FILE.mhd, "
    "a DICOM series packed as FILE.zip, FILE.tar, FILE.tar.gz, FILE.tgz, or "
    "raw:PATH?dims=X,Y,Z&type=int16&spacing=A,B,C[&endian=little|big][&offset=N]";

// Reads the volume `source` names:
//   phantom:SPEC        MakePhantom(SPEC) (server/phantom/phantom.h)
//   raw:PATH?...        ReadRaw with the options in the query (parse_raw_source.h)
//   FOLDER[?series=S&spacing=MM]  ReadDicomSeries (parse_dicom_source.h)
//   *.nii, *.nii.gz     ReadNifti
//   *.nrrd, *.nhdr      ReadNrrd
//   *.mha, *.mhd        ReadMetaImage
//   *.zip, *.tar, *.tar.gz, *.tgz  ExtractArchive into a private temporary
//                       folder, then ReadDicomSeries (the largest CT/MR series)
// Extensions are matched case-insensitively. Every reader checks `limits`
// before allocating. The volume's source() is set to `source`. Errors: those
// of the reader; InvalidArgument listing the forms above for anything else.
// `progress` (optional) hears fractions from 0 to 1, never decreasing:
// 0..0.8 while the file (or the folder's files) is read, 1 once the volume
// is made; nothing more after an error.
Result<Volume> ReadVolume(std::string_view source, const VolumeLimits& limits,
                          const ProgressFn& progress = {});

// Whether ReadVolume reads a file of this name (case-insensitive) as a
// volume file (NIfTI, NRRD, MetaImage: the extensions above), or as an
// archive of a DICOM series.
bool IsVolumeFileName(std::string_view name);
bool IsArchiveName(std::string_view name);

}  // namespace vpm

#include "server/io/read_volume.h"

#include <filesystem>
#include <string>
#include <optional>

#include "server/io/header_text.h"
#include "server/io/parse_dicom_source.h"
#include "server/io/parse_raw_source.h"
#include "server/phantom/phantom.h"
#include "server/io/read_dicom_series.h"
#include "server/io/read_metaimage.h"
#include "server/io/read_nifti.h"
#include "server/io/read_nrrd.h"
#include "server/io/read_raw.h"

namespace vpm {
namespace {

bool EndsWith(const std::string& text, std::string_view suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

Result<Volume> ReadByKind(std::string_view source, const VolumeLimits& limits) {
  if (source.starts_with("phantom:")) return MakePhantom(source.substr(8), limits);
  if (source.starts_with("raw:")) {
    ASSIGN_OR_RETURN(const RawSource raw, ParseRawSource(source));
    return ReadRaw(raw.path, raw.options, limits);
  }
  ASSIGN_OR_RETURN(const std::optional<DicomSource> dicom, ParseDicomSource(source));
  if (dicom.has_value()) return ReadDicomSeries(dicom->folder, limits, dicom->options);
  const std::filesystem::path path{std::string(source)};
  const std::string lower = ToLowerAscii(source);
  if (EndsWith(lower, ".nii") || EndsWith(lower, ".nii.gz")) return ReadNifti(path, limits);
  if (EndsWith(lower, ".nrrd") || EndsWith(lower, ".nhdr")) return ReadNrrd(path, limits);
  if (EndsWith(lower, ".mha") || EndsWith(lower, ".mhd")) return ReadMetaImage(path, limits);
  return absl::InvalidArgumentError(StrCat("unknown volume source \"",
                                                 std::string(source.substr(0, 200)), "\"; use ",
                                                 std::string(kVolumeSourceForms)));
}

}  // namespace

Result<Volume> ReadVolume(std::string_view source, const VolumeLimits& limits,
                          const ProgressFn& progress) {
  const ProgressFn monotone = MonotoneProgress(progress);
  // Reading takes most of a load; decoding and converting the rest.
  const ProgressFn reading = SubProgress(monotone, 0.0, 0.8);
  VolumeLimits with_progress = limits;
  if (reading) with_progress.read_progress = &reading;
  if (monotone) monotone(0.0, "reading");
  ASSIGN_OR_RETURN(Volume volume, ReadByKind(source, with_progress));
  volume.set_source(std::string(source));
  if (monotone) monotone(1.0, "read");
  return volume;
}

}  // namespace vpm

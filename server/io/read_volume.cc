#include "server/io/read_volume.h"

#include <filesystem>
#include <string>
#include <optional>

#include <stdlib.h>

#include "server/io/extract_archive.h"
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


// A DICOM series packed in an archive: unpacked into a private temporary
// folder (mode 0700), read as a DICOM folder, the folder removed. Messages
// name the archive, never the folder.
Result<Volume> ReadDicomArchive(const std::filesystem::path& path, const VolumeLimits& limits) {
  namespace fs = std::filesystem;
  std::string pattern = (fs::temp_directory_path() / "vpm-archive-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    return absl::ResourceExhaustedError("no room to unpack the archive in the temporary folder");
  }
  const fs::path folder = pattern;
  Result<Volume> volume = [&]() -> Result<Volume> {
    ASSIGN_OR_RETURN(const SourceFile file, OpenSourceFile(path, limits));
    RETURN_IF_ERROR(
        ExtractArchive(file, folder, {.max_bytes = limits.max_bytes}, limits.cancel).status());
    VolumeLimits in_folder = limits;
    in_folder.read_root = folder;
    return ReadDicomSeries(folder, in_folder);
  }();
  std::error_code error;
  fs::remove_all(folder, error);
  if (volume.ok()) return volume;
  std::string message(volume.status().message());
  for (size_t at; (at = message.find(folder.string())) != std::string::npos;) {
    message.replace(at, folder.string().size(), path.filename().string());
  }
  return Status(volume.status().code(), message);
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
  if (IsArchiveName(source)) return ReadDicomArchive(path, limits);
  return absl::InvalidArgumentError(StrCat("unknown volume source \"",
                                                 std::string(source.substr(0, 200)), "\"; use ",
                                                 std::string(kVolumeSourceForms)));
}

}  // namespace

bool IsVolumeFileName(std::string_view name) {
  const std::string lower = ToLowerAscii(name);
  for (std::string_view s : {".nii", ".nii.gz", ".nrrd", ".nhdr", ".mha", ".mhd"}) {
    if (EndsWith(lower, s)) return true;
  }
  return false;
}

bool IsArchiveName(std::string_view name) {
  const std::string lower = ToLowerAscii(name);
  return EndsWith(lower, ".zip") || EndsWith(lower, ".tar") || EndsWith(lower, ".tar.gz") ||
         EndsWith(lower, ".tgz");
}

Result<Volume> ReadVolume(std::string_view source, const VolumeLimits& limits,
                          const ProgressFn& progress) {
  const ProgressFn monotone = MonotoneProgress(progress);
  // Reading takes most of a load; decoding and converting the rest.
  const ProgressFn reading = SubProgress(monotone, 0.0, 0.8);
  VolumeLimits with_progress = limits;
  if (reading) with_progress.read_progress = &reading;
  if (monotone) monotone(0.0, "reading");
  ASSIGN_OR_RETURN(Volume volume, ReadByKind(source, with_progress));
  // A cancel that came after the reader's last poll still wins: the caller
  // asked for nothing, and gets the token's status rather than a volume.
  RETURN_IF_ERROR(limits.cancel.Check());
  volume.set_source(std::string(source));
  if (monotone) monotone(1.0, "read");
  return volume;
}

}  // namespace vpm

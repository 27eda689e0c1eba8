#include "server/io/list_dicom_series.h"

#include <algorithm>
#include <map>
#include <optional>
#include <system_error>
#include <tuple>

#include "server/common/prefix_status.h"
#include "server/io/folder_read_budget.h"
#include "server/io/header_text.h"
#include "server/io/read_dicom_slice.h"

namespace vpm {
namespace {

Result<std::vector<std::filesystem::path>> ListFiles(const std::filesystem::path& folder) {
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) {
    return absl::NotFoundError(StrCat(folder.string(), ": no such folder"));
  }
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (entry.is_regular_file(ec)) files.push_back(entry.path());
  }
  if (ec) return absl::InvalidArgumentError(StrCat(folder.string(), ": cannot list files"));
  std::sort(files.begin(), files.end());
  return files;
}

std::string Describe(const DicomSeriesSummary& s, size_t index) {
  return StrCat(index + 1, " = ", s.uid.empty() ? "(no UID)" : s.uid, " (",
                s.not_a_volume_reason.empty() ? s.modality : s.not_a_volume_reason, ", ", s.images,
                " images)");
}

std::string ListChoices(const std::vector<DicomSeriesSummary>& series) {
  std::string out;
  for (size_t n = 0; n < series.size(); ++n) {
    StrAppend(&out, n == 0 ? "" : ", ", Describe(series[n], n));
  }
  return out;
}

bool IsCtOrMr(const DicomSeriesSummary& s) { return s.modality == "CT" || s.modality == "MR"; }

}  // namespace

Result<std::vector<DicomSeriesSummary>> ListDicomSeries(const std::filesystem::path& folder,
                                                        const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<std::filesystem::path> files, ListFiles(folder));
  FolderReadBudget budget(folder, limits);
  // Key: (SeriesNumber, UID, reason), which is also the listing order.
  std::map<std::tuple<int64_t, std::string, std::string>, DicomSeriesSummary> groups;
  for (const std::filesystem::path& path : files) {
    RETURN_IF_ERROR(limits.cancel.Check());
    // A look at the prefix first, so that large non-DICOM files in the
    // folder (a PDF report, a video) are neither read nor counted.
    ASSIGN_OR_RETURN(const std::vector<uint8_t> prefix, ReadFilePrefix(path, 132, limits));
    if (!LooksLikeDicom(prefix)) continue;
    ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, budget.Read(path));
    Result<std::vector<DicomSlice>> frames =
        ParseDicomFrames(bytes, limits, DicomDecode::kHeaderOnly);
    if (!frames.ok()) return PrefixStatus(frames.status(), path.string());
    const DicomSlice* slice = &frames->front();  // every frame has the file's identity
    if (!slice->is_image) continue;
    DicomSeriesSummary& s =
        groups[{slice->series_number, slice->series_uid, slice->not_a_slice_reason}];
    if (s.files.empty()) {
      s.uid = slice->series_uid;
      s.description = slice->series_description;
      s.modality = slice->modality;
      s.series_number = slice->series_number;
      s.columns = slice->columns;
      s.rows = slice->rows;
      s.not_a_volume_reason = slice->not_a_slice_reason;
    }
    s.files.push_back(path);
    s.images += static_cast<int64_t>(frames->size());
  }
  if (groups.empty()) {
    return absl::InvalidArgumentError(
        StrCat(folder.string(), ": holds no DICOM images (", files.size(), " files checked)"));
  }
  std::vector<DicomSeriesSummary> out;
  for (auto& [key, s] : groups) out.push_back(std::move(s));
  return out;
}

Result<size_t> ChooseDicomSeries(const std::vector<DicomSeriesSummary>& series,
                                 std::string_view selector) {
  std::optional<size_t> chosen;
  if (selector.empty()) {
    const auto better = [](const DicomSeriesSummary& a, const DicomSeriesSummary& b) {
      const auto voxels = [](const DicomSeriesSummary& s) { return s.columns * s.rows * s.images; };
      return std::make_tuple(IsCtOrMr(a), voxels(a)) > std::make_tuple(IsCtOrMr(b), voxels(b));
    };
    for (size_t n = 0; n < series.size(); ++n) {
      if (!series[n].not_a_volume_reason.empty()) continue;
      if (!chosen.has_value() || better(series[n], series[*chosen])) chosen = n;
    }
    if (!chosen.has_value()) {
      return absl::InvalidArgumentError(
          StrCat("holds no series of slices, only localizers or secondary captures: ",
                 ListChoices(series)));
    }
    return *chosen;
  }
  const std::optional<int64_t> index = ParseInt(selector);
  for (size_t n = 0; n < series.size() && !chosen.has_value(); ++n) {
    if (series[n].uid == selector && series[n].not_a_volume_reason.empty()) chosen = n;
  }
  if (!chosen.has_value() && index.has_value() && *index >= 1 &&
      *index <= static_cast<int64_t>(series.size())) {
    chosen = static_cast<size_t>(*index - 1);
  }
  if (!chosen.has_value()) {
    return absl::InvalidArgumentError(StrCat("no series \"", std::string(selector.substr(0, 80)),
                                             "\" (a UID or 1..", series.size(),
                                             "); the folder holds ", ListChoices(series)));
  }
  const DicomSeriesSummary& s = series[*chosen];
  if (!s.not_a_volume_reason.empty()) {
    return absl::InvalidArgumentError(
        StrCat("series ", Describe(s, *chosen), " is a ", s.not_a_volume_reason, ", not a volume"));
  }
  return *chosen;
}

}  // namespace vpm

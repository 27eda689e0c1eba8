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
#include "server/io/split_dicom_stacks.h"

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
                s.not_a_volume_reason.empty() ? s.modality : s.not_a_volume_reason, ", ",
                s.stack.empty() ? "" : StrCat(s.stack, ", "), s.images, " images)");
}

// A series and the split's view of its images: where each one is (the
// index of its file in summary.files, and its frame).
struct Group {
  DicomSeriesSummary summary;
  std::vector<StackImage> images;
  std::vector<std::pair<size_t, int64_t>> image_at;
};

void AddImages(const std::vector<DicomSlice>& frames, Group& group) {
  const size_t file = group.summary.files.size() - 1;
  for (size_t f = 0; f < frames.size(); ++f) {
    const auto& o = frames[f].orientation;
    StackImage image{.attributes = frames[f].stack, .position_mm = frames[f].position_mm};
    const glm::dvec3 normal =
        glm::cross(glm::dvec3(o[0], o[1], o[2]), glm::dvec3(o[3], o[4], o[5]));
    if (glm::length(normal) > 0.5) image.normal_lps = glm::normalize(normal);
    group.images.push_back(image);
    group.image_at.emplace_back(file, static_cast<int64_t>(f));
  }
}

// The summary of one stack: its files and, where it takes only some frames
// of a file, which.
DicomSeriesSummary StackSummary(const Group& group, const DicomStack& stack) {
  DicomSeriesSummary s = group.summary;
  s.stack = stack.label;
  s.files.clear();
  s.images = static_cast<int64_t>(stack.images.size());
  std::vector<size_t> frames_in_file(group.summary.files.size(), 0);
  for (const auto& at : group.image_at) ++frames_in_file[at.first];
  std::vector<size_t> chosen;  // indices into group.summary.files
  for (size_t n : stack.images) {
    const auto [file, frame] = group.image_at[n];
    if (chosen.empty() || chosen.back() != file) {
      chosen.push_back(file);
      s.files.push_back(group.summary.files[file]);
      s.frames.emplace_back();
    }
    s.frames.back().push_back(frame);
  }
  bool partial = false;
  for (size_t k = 0; k < chosen.size(); ++k) {
    partial |= s.frames[k].size() < frames_in_file[chosen[k]];
  }
  if (!partial) s.frames.clear();
  return s;
}

// The group's entries: one, or one per stack where its positions repeat.
void AppendStacks(Group& group, std::vector<DicomSeriesSummary>& out) {
  const std::vector<DicomStack> stacks = group.summary.not_a_volume_reason.empty()
                                             ? SplitDicomStacks(group.images)
                                             : std::vector<DicomStack>(1);
  if (stacks.size() == 1) {
    out.push_back(std::move(group.summary));
    return;
  }
  for (const DicomStack& stack : stacks) out.push_back(StackSummary(group, stack));
}

std::string ListChoices(const std::vector<DicomSeriesSummary>& series) {
  std::string out;
  for (size_t n = 0; n < series.size(); ++n) {
    StrAppend(&out, n == 0 ? "" : ", ", Describe(series[n], n));
  }
  return out;
}

// Where a folder without images has subfolders (a CD or USB export keeps
// each series in a folder of its own, DICOM/ST000/SE000/...), says so and
// names up to three; else "".
std::string SubfolderHint(const std::filesystem::path& folder) {
  constexpr size_t kShown = 3;
  constexpr size_t kNameChars = 40;
  std::error_code ec;
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (entry.is_directory(ec)) names.push_back(entry.path().filename().string());
  }
  if (names.empty()) return "";
  std::sort(names.begin(), names.end());
  std::string shown;
  for (size_t n = 0; n < std::min(names.size(), kShown); ++n) {
    StrAppend(&shown, n == 0 ? "" : ", ", names[n].substr(0, kNameChars));
  }
  const bool one = names.size() == 1;
  return StrCat("; its ", names.size(), one ? " subfolder (" : " subfolders (", shown,
                names.size() > kShown ? ", ..." : "", one ? ") is" : ") are",
                " not read: give the folder that holds the series' files");
}

bool IsCtOrMr(const DicomSeriesSummary& s) { return s.modality == "CT" || s.modality == "MR"; }

}  // namespace

Result<std::vector<DicomSeriesSummary>> ListDicomSeries(const std::filesystem::path& folder,
                                                        const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<std::filesystem::path> files, ListFiles(folder));
  FolderReadBudget budget(folder, limits);
  // Key: (SeriesNumber, UID, reason), which is also the listing order.
  std::map<std::tuple<int64_t, std::string, std::string>, Group> groups;
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
    Group& group = groups[{slice->series_number, slice->series_uid, slice->not_a_slice_reason}];
    DicomSeriesSummary& s = group.summary;
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
    AddImages(*frames, group);
  }
  if (groups.empty()) {
    return absl::InvalidArgumentError(StrCat(folder.string(), ": holds no DICOM images (",
                                             files.size(), " files checked)",
                                             SubfolderHint(folder)));
  }
  std::vector<DicomSeriesSummary> out;
  for (auto& [key, group] : groups) AppendStacks(group, out);
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

bool SameDicomSeries(const DicomSeriesSummary& a, const DicomSeriesSummary& b) {
  return a.uid == b.uid && a.series_number == b.series_number &&
         a.not_a_volume_reason == b.not_a_volume_reason;
}

std::vector<size_t> DicomSeriesStacks(const std::vector<DicomSeriesSummary>& series,
                                      size_t chosen) {
  std::vector<size_t> out;
  for (size_t n = 0; n < series.size(); ++n) {
    if (n == chosen ||
        (!series[chosen].stack.empty() && SameDicomSeries(series[n], series[chosen]))) {
      out.push_back(n);
    }
  }
  return out;
}

std::string ListDicomStacks(const std::vector<DicomSeriesSummary>& series,
                            const std::vector<size_t>& stacks) {
  std::string out;
  for (size_t n = 0; n < stacks.size(); ++n) {
    StrAppend(&out, n == 0 ? "" : ", ", n + 1, " = ", series[stacks[n]].stack);
  }
  return out;
}

Result<size_t> ChooseDicomStack(const std::vector<DicomSeriesSummary>& series, size_t chosen,
                                int64_t stack) {
  if (stack == 0) return chosen;
  const std::vector<size_t> stacks = DicomSeriesStacks(series, chosen);
  if (stack >= 1 && stack <= static_cast<int64_t>(stacks.size())) {
    return stacks[static_cast<size_t>(stack - 1)];
  }
  if (stacks.size() == 1) {
    return absl::InvalidArgumentError(StrCat("no stack ", stack, ": series ",
                                             series[chosen].uid.substr(0, 64), " holds one stack"));
  }
  return absl::InvalidArgumentError(
      StrCat("no stack ", stack, ": series ", series[chosen].uid.substr(0, 64), " holds ",
             stacks.size(), " stacks (", ListDicomStacks(series, stacks), ")"));
}

}  // namespace vpm

#include "server/io/read_dicom_series.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <system_error>
#include <vector>

#include "server/common/prefix_status.h"
#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"

namespace vpm {
namespace {

constexpr double kGapTolerance = 0.01;          // relative to the mean gap
constexpr double kOrientationTolerance = 1e-4;  // per direction-cosine component
constexpr double kSpacingTolerance = 1e-4;      // relative

struct NamedSlice {
  std::string file;
  DicomSlice slice;
  double position_along_normal = 0.0;
};

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

// Parses every DICOM image in the folder, keeping the running totals under
// the caps so that a folder of many files cannot exhaust memory.
Result<std::vector<NamedSlice>> ParseAll(const std::filesystem::path& folder,
                                         const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<std::filesystem::path> files, ListFiles(folder));
  std::vector<NamedSlice> slices;
  int64_t bytes_read = 0;
  int64_t voxels = 0;
  for (const std::filesystem::path& path : files) {
    // A look at the prefix first, so that large non-DICOM files in the
    // folder (a PDF report, a video) are neither read nor counted.
    ASSIGN_OR_RETURN(const std::vector<uint8_t> prefix, ReadFilePrefix(path, 132));
    if (!LooksLikeDicom(prefix)) continue;
    VolumeLimits remaining = limits;
    remaining.max_bytes = limits.max_bytes - bytes_read;
    Result<std::vector<uint8_t>> bytes = ReadFileBytes(path, remaining);
    if (bytes.status().code() == absl::StatusCode::kResourceExhausted) {
      return absl::ResourceExhaustedError(StrCat(
          folder.string(), ": the DICOM files hold over ", limits.max_bytes, " bytes (the cap)"));
    }
    if (!bytes.ok()) return bytes.status();
    bytes_read += static_cast<int64_t>(bytes->size());
    Result<DicomSlice> slice = ParseDicomSlice(*bytes, limits);
    if (!slice.ok()) return PrefixStatus(slice.status(), path.string());
    if (!slice->is_image) continue;
    voxels += slice->rows * slice->columns;
    if (voxels > limits.max_voxels) {
      return absl::ResourceExhaustedError(StrCat(folder.string(), ": the slices hold over ",
                                                       limits.max_voxels, " voxels (the cap)"));
    }
    slices.push_back({path.filename().string(), *std::move(slice), 0.0});
  }
  if (slices.empty()) {
    return absl::InvalidArgumentError(StrCat(folder.string(), ": holds no DICOM images (",
                                                   files.size(), " files checked)"));
  }
  return slices;
}

Status CheckOneSeries(const std::filesystem::path& folder, const std::vector<NamedSlice>& slices) {
  std::map<std::string, int> series;
  for (const NamedSlice& s : slices) ++series[s.slice.series_uid];
  if (series.size() == 1) return absl::OkStatus();
  std::string uids;
  for (const auto& [uid, count] : series) {
    StrAppend(&uids, uids.empty() ? "" : ", ", uid.empty() ? "(none)" : uid, " (", count,
                    " files)");
  }
  return absl::InvalidArgumentError(StrCat("folder ", folder.string(), " holds ",
                                                 series.size(), " series (UIDs ", uids,
                                                 "); pass one series per folder"));
}

Status CheckSameFrame(const NamedSlice& first, const NamedSlice& other) {
  const DicomSlice& a = first.slice;
  const DicomSlice& b = other.slice;
  const std::string pair = StrCat(" differ between ", first.file, " and ", other.file);
  if (a.rows != b.rows || a.columns != b.columns) {
    return absl::InvalidArgumentError(StrCat("Rows/Columns (", a.rows, "x", a.columns, " vs ",
                                                   b.rows, "x", b.columns, ")", pair));
  }
  for (int n = 0; n < 2; ++n) {
    if (std::abs(a.pixel_spacing_mm[n] - b.pixel_spacing_mm[n]) >
        kSpacingTolerance * std::abs(a.pixel_spacing_mm[n])) {
      return absl::InvalidArgumentError(StrCat("PixelSpacing values", pair));
    }
  }
  for (int n = 0; n < 6; ++n) {
    if (std::abs(a.orientation[n] - b.orientation[n]) > kOrientationTolerance) {
      return absl::InvalidArgumentError(StrCat("ImageOrientationPatient values", pair));
    }
  }
  return absl::OkStatus();
}

// Sorts along the normal and returns the mean gap (0 for one slice).
Result<double> SortAndCheckGaps(std::vector<NamedSlice>& slices, const glm::dvec3& normal) {
  for (NamedSlice& s : slices) s.position_along_normal = glm::dot(s.slice.position_mm, normal);
  std::sort(slices.begin(), slices.end(), [](const NamedSlice& a, const NamedSlice& b) {
    return a.position_along_normal < b.position_along_normal;
  });
  const size_t n = slices.size();
  if (n < 2) return 0.0;
  const double mean_gap =
      (slices.back().position_along_normal - slices.front().position_along_normal) / (n - 1);
  // Duplicates first: they also make the gaps uneven, but deserve their own message.
  for (size_t k = 1; k < n; ++k) {
    const NamedSlice& a = slices[k - 1];
    const NamedSlice& b = slices[k];
    const double gap = b.position_along_normal - a.position_along_normal;
    if (gap <= kGapTolerance * mean_gap || gap < 1e-6) {
      return absl::InvalidArgumentError(
          StrCat("duplicate slice position: ", a.file, " and ", b.file, " are both at ",
                       a.position_along_normal, " mm along the slice normal"));
    }
  }
  for (size_t k = 1; k < n; ++k) {
    const NamedSlice& a = slices[k - 1];
    const NamedSlice& b = slices[k];
    const double gap = b.position_along_normal - a.position_along_normal;
    if (std::abs(gap - mean_gap) > kGapTolerance * mean_gap) {
      return absl::InvalidArgumentError(StrCat(
          "uneven slice spacing: the gap between ", a.file, " and ", b.file, " is ", gap,
          " mm but the mean gap is ", mean_gap, " mm (tolerance 1%); missing or extra slices?"));
    }
  }
  return mean_gap;
}

// Every slice must sit on the line through the first along the normal.
Status CheckStacked(const std::vector<NamedSlice>& slices, const glm::dvec3& normal) {
  const glm::dvec3 p0 = slices.front().slice.position_mm;
  for (const NamedSlice& s : slices) {
    const glm::dvec3 d = s.slice.position_mm - p0;
    const double along = glm::dot(d, normal);
    const double across = glm::length(d - along * normal);
    if (across > kGapTolerance * std::abs(along) + 1e-3) {
      return absl::UnimplementedError(
          StrCat(s.file, " is shifted ", across,
                       " mm across the slice normal (tilted gantry or "
                       "sheared stack); such series are not supported"));
    }
  }
  return absl::OkStatus();
}

Result<Volume> AssembleSeries(const std::filesystem::path& folder, std::vector<NamedSlice> slices,
                              const VolumeLimits& limits) {
  for (const NamedSlice& s : slices) RETURN_IF_ERROR(CheckSameFrame(slices.front(), s));
  const DicomSlice& first = slices.front().slice;
  const glm::dvec3 row_dir(first.orientation[0], first.orientation[1], first.orientation[2]);
  const glm::dvec3 col_dir(first.orientation[3], first.orientation[4], first.orientation[5]);
  const glm::dvec3 cross = glm::cross(row_dir, col_dir);
  const double cross_length = glm::length(cross);
  if (!(cross_length > 0.5)) {
    return absl::InvalidArgumentError(
        "ImageOrientationPatient row and column directions are not perpendicular unit vectors");
  }
  const glm::dvec3 normal = cross / cross_length;
  ASSIGN_OR_RETURN(const double mean_gap, SortAndCheckGaps(slices, normal));
  RETURN_IF_ERROR(CheckStacked(slices, normal));
  const DicomSlice& base = slices.front().slice;
  VolumeGeometry g;
  g.dims = {base.columns, base.rows, static_cast<int64_t>(slices.size())};
  const double thickness = base.slice_thickness_mm > 0.0 ? base.slice_thickness_mm : 1.0;
  g.spacing_mm = {base.pixel_spacing_mm[1], base.pixel_spacing_mm[0],
                  slices.size() > 1 ? mean_gap : thickness};
  g.origin_mm = base.position_mm;
  g.direction = glm::dmat3(row_dir, col_dir, normal);
  RETURN_IF_ERROR(ValidateGeometry(g, limits));
  std::vector<float> values;
  values.reserve(static_cast<size_t>(g.voxel_count()));
  for (NamedSlice& s : slices) {
    values.insert(values.end(), s.slice.values.begin(), s.slice.values.end());
    s.slice.values = {};
  }
  ASSIGN_OR_RETURN(Volume volume, Volume::Create(g, std::move(values), limits));
  volume.set_source(folder.string());
  return volume;
}

}  // namespace

Result<Volume> ReadDicomSeries(const std::filesystem::path& folder, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(std::vector<NamedSlice> slices, ParseAll(folder, limits));
  RETURN_IF_ERROR(CheckOneSeries(folder, slices));
  Result<Volume> volume = AssembleSeries(folder, std::move(slices), limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), folder.string());
  return volume;
}

}  // namespace vpm

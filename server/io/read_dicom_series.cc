#include "server/io/read_dicom_series.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "server/common/prefix_status.h"
#include "server/io/convert_voxels.h"
#include "server/io/folder_read_budget.h"
#include "server/io/list_dicom_series.h"
#include "server/io/read_dicom_origin.h"
#include "server/io/read_dicom_slice.h"
#include "server/io/resample_sheared_stack.h"

namespace vpm {
namespace {

constexpr double kGapTolerance = 0.01;          // relative to the mean gap
constexpr double kOrientationTolerance = 1e-4;  // per direction-cosine component
constexpr double kSpacingTolerance = 1e-4;      // relative
// A gap this many times the smallest one suggests missing slices: still
// interpolated across, but said in the notes.
constexpr double kLargeGapFactor = 5.0;

struct NamedSlice {
  std::string file;
  DicomSlice slice;
  glm::dvec3 position_in_frame_mm{0.0};  // (along row dir, along column dir, along normal)
};

// One decimal, for notes meant to be read: "18.5".
double Round1(double x) { return std::round(x * 10.0) / 10.0; }

// Whether frame `frame` of file `file` of `series` belongs to it (a stack
// may take only some frames of a multi-frame file).
bool InStack(const DicomSeriesSummary& series, size_t file, size_t frame) {
  if (series.frames.empty()) return true;
  const std::vector<int64_t>& frames = series.frames[file];
  return std::find(frames.begin(), frames.end(), static_cast<int64_t>(frame)) != frames.end();
}

// Decodes the chosen series' files, holding bytes and voxels to the caps.
Result<std::vector<NamedSlice>> DecodeSeries(const std::filesystem::path& folder,
                                             const DicomSeriesSummary& series,
                                             const VolumeLimits& limits) {
  FolderReadBudget budget(folder, limits);
  std::vector<NamedSlice> slices;
  int64_t voxels = 0;
  // Progress by files, not by each file's bytes.
  VolumeLimits file_limits = limits;
  file_limits.read_progress = nullptr;
  for (size_t file = 0; file < series.files.size(); ++file) {
    RETURN_IF_ERROR(limits.cancel.Check());
    const std::filesystem::path& path = series.files[file];
    if (limits.read_progress != nullptr && *limits.read_progress) {
      (*limits.read_progress)(double(file) / double(series.files.size()), "reading DICOM");
    }
    ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, budget.Read(path));
    Result<std::vector<DicomSlice>> frames =
        ParseDicomFrames(bytes, file_limits, DicomDecode::kPixels);
    if (!frames.ok()) return PrefixStatus(frames.status(), path.string());
    for (size_t f = 0; f < frames->size(); ++f) {
      if (!InStack(series, file, f)) continue;
      DicomSlice& slice = (*frames)[f];
      voxels += slice.rows * slice.columns;
      // The budget as int16, the least a volume of these slices takes.
      if (voxels * 2 > limits.max_volume_bytes) {
        return absl::ResourceExhaustedError(
            StrCat(folder.string(), ": the slices hold over ", voxels, " voxels (", voxels * 2,
                   " bytes as int16), over the cap of ", limits.max_volume_bytes,
                   " bytes on one volume (--max-volume-bytes)"));
      }
      const std::string name = path.filename().string();
      slices.push_back({frames->size() == 1 ? name : StrCat(name, " frame ", f + 1),
                        std::move(slice), glm::dvec3(0.0)});
    }
  }
  return slices;
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

// Columns: row direction, column direction, slice normal (world LPS).
Result<glm::dmat3> SliceFrame(const DicomSlice& first) {
  const glm::dvec3 row_dir(first.orientation[0], first.orientation[1], first.orientation[2]);
  const glm::dvec3 col_dir(first.orientation[3], first.orientation[4], first.orientation[5]);
  const glm::dvec3 cross = glm::cross(row_dir, col_dir);
  const double cross_length = glm::length(cross);
  if (!(cross_length > 0.5)) {
    return absl::InvalidArgumentError(
        "ImageOrientationPatient row and column directions are not perpendicular unit vectors");
  }
  return glm::dmat3(row_dir, col_dir, cross / cross_length);
}

// Sorts along the normal; duplicate positions are an error.
Status SortAlongNormal(std::vector<NamedSlice>& slices, const glm::dmat3& frame) {
  for (NamedSlice& s : slices) {
    s.position_in_frame_mm = glm::transpose(frame) * s.slice.position_mm;
  }
  std::sort(slices.begin(), slices.end(), [](const NamedSlice& a, const NamedSlice& b) {
    return a.position_in_frame_mm.z < b.position_in_frame_mm.z;
  });
  if (slices.size() < 2) return absl::OkStatus();
  const double mean_gap =
      (slices.back().position_in_frame_mm.z - slices.front().position_in_frame_mm.z) /
      static_cast<double>(slices.size() - 1);
  for (size_t k = 1; k < slices.size(); ++k) {
    const NamedSlice& a = slices[k - 1];
    const NamedSlice& b = slices[k];
    const double gap = b.position_in_frame_mm.z - a.position_in_frame_mm.z;
    if (gap <= kGapTolerance * mean_gap || gap < 1e-6) {
      return absl::InvalidArgumentError(StrCat("duplicate slice position: ", a.file, " and ",
                                               b.file, " are both at ", a.position_in_frame_mm.z,
                                               " mm along the slice normal (two images at one "
                                               "place, and no echo, phase, b-value, image type "
                                               "or acquisition number sets them apart)"));
    }
  }
  return absl::OkStatus();
}

// What the sorted stack looks like: its gaps and its shear.
struct StackShape {
  double mean_gap_mm = 0.0;
  double min_gap_mm = 0.0;
  double max_gap_mm = 0.0;
  size_t max_gap_at = 0;  // the gap between slices max_gap_at - 1 and max_gap_at
  bool uneven = false;
  double tilt_deg = 0.0;  // angle between the stack's axis and the slice normal
  bool sheared = false;
};

StackShape MeasureStack(const std::vector<NamedSlice>& slices) {
  StackShape shape;
  const size_t n = slices.size();
  const glm::dvec3 first = slices.front().position_in_frame_mm;
  shape.mean_gap_mm = (slices.back().position_in_frame_mm.z - first.z) / (n - 1);
  shape.min_gap_mm = shape.mean_gap_mm;
  for (size_t k = 1; k < n; ++k) {
    const double gap = slices[k].position_in_frame_mm.z - slices[k - 1].position_in_frame_mm.z;
    shape.uneven |= std::abs(gap - shape.mean_gap_mm) > kGapTolerance * shape.mean_gap_mm;
    shape.min_gap_mm = std::min(shape.min_gap_mm, gap);
    if (gap > shape.max_gap_mm) {
      shape.max_gap_mm = gap;
      shape.max_gap_at = k;
    }
    // Every slice must sit on the normal through the first, else the stack is sheared.
    const glm::dvec3 d = slices[k].position_in_frame_mm - first;
    const double across = glm::length(glm::dvec2(d));
    shape.sheared |= across > kGapTolerance * std::abs(d.z) + 1e-3;
  }
  const glm::dvec3 d = slices.back().position_in_frame_mm - first;
  shape.tilt_deg = glm::degrees(std::atan2(glm::length(glm::dvec2(d)), d.z));
  return shape;
}

// The notes that say what was corrected, for `vpm volume info`.
void AddResampleNotes(const std::vector<NamedSlice>& slices, const StackShape& shape,
                      double spacing_mm, Volume& volume) {
  if (shape.sheared) {
    volume.add_note(StrCat("gantry tilt ", Round1(shape.tilt_deg),
                           " deg (slices shifted across the normal): resampled onto the "
                           "orthogonal grid of row, column and normal directions"));
  }
  if (shape.uneven) {
    volume.add_note(StrCat("slice gaps ", Round1(shape.min_gap_mm), " to ",
                           Round1(shape.max_gap_mm), " mm: resampled to ", spacing_mm, " mm"));
  } else if (std::abs(spacing_mm - shape.mean_gap_mm) > kGapTolerance * shape.mean_gap_mm) {
    volume.add_note(StrCat("slice gap ", shape.mean_gap_mm, " mm: resampled to ", spacing_mm,
                           " mm (spacing option)"));
  }
  if (shape.max_gap_mm > kLargeGapFactor * shape.min_gap_mm) {
    volume.add_note(StrCat("the gap of ", Round1(shape.max_gap_mm), " mm between ",
                           slices[shape.max_gap_at - 1].file, " and ",
                           slices[shape.max_gap_at].file, " is over ", kLargeGapFactor,
                           " times the smallest (", Round1(shape.min_gap_mm),
                           " mm): missing slices? linearly interpolated across"));
  }
}

Result<Volume> StackAsStored(std::vector<NamedSlice>& slices, const glm::dmat3& frame,
                             double slice_spacing_mm, const VolumeLimits& limits) {
  const DicomSlice& base = slices.front().slice;
  VolumeGeometry g;
  g.dims = {base.columns, base.rows, static_cast<int64_t>(slices.size())};
  g.spacing_mm = {base.pixel_spacing_mm[1], base.pixel_spacing_mm[0], slice_spacing_mm};
  g.origin_mm = base.position_mm;
  g.direction = frame;
  RETURN_IF_ERROR(ValidateGeometry(g, limits));
  // int16 when every slice holds integers that fit with one offset (CT in
  // HU after the rescale): the stack is built slice by slice, each slice's
  // floats freed as it goes in.
  IntegerRangeOfFloats range;
  for (const NamedSlice& s : slices) {
    for (float v : s.slice.values) range.Add(v);
  }
  RETURN_IF_ERROR(limits.cancel.Check());
  const std::optional<int32_t> offset = range.Offset();
  if (!offset) {
    std::vector<float> values;
    values.reserve(static_cast<size_t>(g.voxel_count()));
    for (NamedSlice& s : slices) {
      values.insert(values.end(), s.slice.values.begin(), s.slice.values.end());
      s.slice.values = {};
    }
    std::string note;
    ASSIGN_OR_RETURN(VoxelValues voxels, FloatsToVoxels(std::move(values), g, limits, &note));
    ASSIGN_OR_RETURN(Volume volume, Volume::Create(g, std::move(voxels), limits));
    if (!note.empty()) volume.add_note(std::move(note));
    return volume;
  }
  RETURN_IF_ERROR(ValidateGeometry(g, limits, VoxelEncoding::kInt16));
  std::vector<int16_t> stored;
  stored.reserve(static_cast<size_t>(g.voxel_count()));
  for (NamedSlice& s : slices) {
    RETURN_IF_ERROR(limits.cancel.Check());
    for (float v : s.slice.values) stored.push_back(static_cast<int16_t>(int32_t(v) - *offset));
    s.slice.values = {};
  }
  ASSIGN_OR_RETURN(VoxelValues voxels, VoxelValues::Int16(std::move(stored), *offset));
  return Volume::Create(g, std::move(voxels), limits);
}

Result<Volume> Resample(const std::vector<NamedSlice>& slices, const glm::dmat3& frame,
                        double slice_spacing_mm, const VolumeLimits& limits) {
  const DicomSlice& base = slices.front().slice;
  ShearedStack stack;
  stack.columns = base.columns;
  stack.rows = base.rows;
  stack.pixel_spacing_mm = {base.pixel_spacing_mm[1], base.pixel_spacing_mm[0]};
  stack.frame = frame;
  // Outside the stack: the series' minimum (air, or the scanner's own
  // padding value), so that the added margins read as background.
  float fill = std::numeric_limits<float>::max();
  for (const NamedSlice& s : slices) {
    stack.slices.push_back({s.position_in_frame_mm, s.slice.values});
    for (float v : s.slice.values) fill = std::isfinite(v) ? std::min(fill, v) : fill;
  }
  return ResampleShearedStack(stack, slice_spacing_mm, fill, limits);
}

Result<Volume> AssembleSeries(std::vector<NamedSlice> slices, const DicomReadOptions& options,
                              const VolumeLimits& limits) {
  for (const NamedSlice& s : slices) RETURN_IF_ERROR(CheckSameFrame(slices.front(), s));
  ASSIGN_OR_RETURN(const glm::dmat3 frame, SliceFrame(slices.front().slice));
  RETURN_IF_ERROR(SortAlongNormal(slices, frame));
  if (slices.size() == 1) {
    const double thickness = slices.front().slice.slice_thickness_mm;
    return StackAsStored(slices, frame, thickness > 0.0 ? thickness : 1.0, limits);
  }
  const StackShape shape = MeasureStack(slices);
  const bool respace = options.spacing_mm > 0.0;
  if (!shape.sheared && !shape.uneven && !respace) {
    return StackAsStored(slices, frame, shape.mean_gap_mm, limits);
  }
  const double spacing_mm =
      respace ? options.spacing_mm : (shape.uneven ? shape.min_gap_mm : shape.mean_gap_mm);
  ASSIGN_OR_RETURN(Volume volume, Resample(slices, frame, spacing_mm, limits));
  AddResampleNotes(slices, shape, spacing_mm, volume);
  return volume;
}

// Which series (and stack) was read, where the folder offered a choice.
void AddChoiceNotes(const std::vector<DicomSeriesSummary>& series, size_t chosen, Volume& volume) {
  const DicomSeriesSummary& s = series[chosen];
  size_t distinct = 0;
  for (size_t n = 0; n < series.size(); ++n) {
    distinct += n == 0 || !SameDicomSeries(series[n - 1], series[n]);
  }
  if (!s.stack.empty()) {
    const std::vector<size_t> stacks = DicomSeriesStacks(series, chosen);
    std::vector<std::string> labels;
    int read = 0;
    for (size_t n = 0; n < stacks.size(); ++n) {
      labels.push_back(series[stacks[n]].stack);
      if (stacks[n] == chosen) read = static_cast<int>(n + 1);
    }
    volume.add_note(StrCat("series ", s.uid, " holds ", stacks.size(), " stacks (",
                           ListDicomStacks(series, stacks), "); read stack ", read, " (", s.stack,
                           ", ", s.images, " slices); stack=N in the source picks another"));
    volume.set_stacks(std::move(labels), read);
  }
  if (distinct > 1) {
    volume.add_note(
        StrCat("the folder holds ", distinct, " series",
               distinct == series.size() ? "" : StrCat(" in ", series.size(), " stacks"),
               "; read series ", chosen + 1, " (", s.uid, ", ", s.modality, " \"", s.description,
               "\", ", s.images, " slices); ?series=N or ?series=UID picks another"));
  }
}

}  // namespace

Result<Volume> ReadDicomSeries(const std::filesystem::path& folder, const VolumeLimits& limits,
                               const DicomReadOptions& options) {
  ASSIGN_OR_RETURN(const std::vector<DicomSeriesSummary> series, ListDicomSeries(folder, limits));
  Result<size_t> chosen = ChooseDicomSeries(series, options.series);
  if (chosen.ok()) chosen = ChooseDicomStack(series, *chosen, options.stack);
  if (!chosen.ok()) return PrefixStatus(chosen.status(), folder.string());
  ASSIGN_OR_RETURN(std::vector<NamedSlice> slices, DecodeSeries(folder, series[*chosen], limits));
  RETURN_IF_ERROR(limits.cancel.Check());
  Result<Volume> volume = AssembleSeries(std::move(slices), options, limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), folder.string());
  AddChoiceNotes(series, *chosen, *volume);
  RETURN_IF_ERROR(limits.cancel.Check());
  // What an export into the same study copies (write_derived_series.h).
  Result<DicomOrigin> origin = ReadDicomOrigin(series[*chosen].files);
  if (!origin.ok()) return PrefixStatus(origin.status(), folder.string());
  volume->set_dicom_origin(std::make_shared<const DicomOrigin>(std::move(*origin)));
  volume->set_source(folder.string());
  return volume;
}

}  // namespace vpm

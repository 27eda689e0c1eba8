// The series a DICOM folder holds, from the files' headers alone.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

struct DicomSeriesSummary {
  std::string uid;          // SeriesInstanceUID ("" if absent)
  std::string description;  // SeriesDescription of the first file
  std::string modality;     // CT, MR, ...
  int64_t series_number = 0;
  int64_t columns = 0;  // of the first file
  int64_t rows = 0;
  // "localizer" or "secondary capture" for images never stacked into a
  // volume (they form a group of their own even when they share the UID of
  // a real series); "" for a series of slices.
  std::string not_a_volume_reason;
  // What sets this stack apart where the series holds several
  // (SplitDicomStacks: "EchoNumbers 2", "coronal"); "" otherwise.
  std::string stack;
  std::vector<std::filesystem::path> files;  // sorted by name
  // Where the stacks of a series share multi-frame files: parallel to
  // `files`, the frames (0-based) of each file that belong to this stack.
  // Empty: every frame of every file.
  std::vector<std::vector<int64_t>> frames;
  int64_t images = 0;  // slices: one per classic file, one per frame of a multi-frame one
};

// Parses the header of every regular DICOM file in `folder` (not its
// subfolders; files without the "DICM" prefix, and DICOM files without pixel
// data such as DICOMDIR or dose reports, are skipped) and groups the images
// by SeriesInstanceUID; a series of several stacks (planes, or echoes,
// phases, b-values at the same positions: SplitDicomStacks) is listed once
// per stack, each with its `stack` label. Order: by SeriesNumber, then UID,
// slices before localizers, then the stacks in their order. The bytes read are held to
// `limits.max_bytes` as a running total. Errors: NotFound (no folder), InvalidArgument (no DICOM
// images, an unreadable file, named), ResourceExhausted, Unimplemented (an image kind
// ParseDicomFrames does not read).
Result<std::vector<DicomSeriesSummary>> ListDicomSeries(const std::filesystem::path& folder,
                                                        const VolumeLimits& limits);

// Index into `series` of the one `selector` names: "" picks the series of
// slices with the most voxels, CT and MR before other modalities (the first
// of equals); else a SeriesInstanceUID (its first stack) or a 1-based index N. InvalidArgument
// naming the choices for an unknown UID or index, or a localizer / secondary capture.
Result<size_t> ChooseDicomSeries(const std::vector<DicomSeriesSummary>& series,
                                 std::string_view selector);

// Whether two entries are stacks of the same series.
bool SameDicomSeries(const DicomSeriesSummary& a, const DicomSeriesSummary& b);

// The entries of `series` that are stacks of series[chosen], in their order
// (one entry, `chosen`, for a series of one stack).
std::vector<size_t> DicomSeriesStacks(const std::vector<DicomSeriesSummary>& series, size_t chosen);

// "1 = EchoNumbers 1, 2 = EchoNumbers 2": the stacks `stacks` (indices into
// `series`, as DicomSeriesStacks gives them) numbered from 1 with their labels.
std::string ListDicomStacks(const std::vector<DicomSeriesSummary>& series,
                            const std::vector<size_t>& stacks);

// Index into `series` of stack `stack` (1-based) of the series of
// series[chosen]; 0 keeps `chosen`. InvalidArgument naming the stacks for
// a number beyond them.
Result<size_t> ChooseDicomStack(const std::vector<DicomSeriesSummary>& series, size_t chosen,
                                int64_t stack);

}  // namespace vpm

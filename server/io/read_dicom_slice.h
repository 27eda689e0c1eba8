// One DICOM file: its slice geometry and pixel values (DCMTK does the parse).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Attributes that can tell apart several stacks of images at the same
// positions in one series (the echoes of an in/opposed-phase MR, the phases
// of a dynamic series, b-values, Dixon's water and fat images), as written
// ("" when absent): the top-level dataset's, and for a frame of an enhanced
// image its functional groups' where they carry one (in brackets).
// split_dicom_stacks.h decides which one splits.
struct DicomStackAttributes {
  std::string echo_numbers;        // EchoNumbers (0018,0086)
  std::string echo_time;           // EchoTime (0018,0081) [EffectiveEchoTime], ms
  std::string temporal_position;   // TemporalPositionIdentifier [TemporalPositionIndex]
  std::string trigger_time;        // TriggerTime (0018,1060), ms
  std::string diffusion_b_value;   // DiffusionBValue (0018,9087), s/mm^2
  std::string stack_id;            // [StackID (0020,9056)]
  std::string image_type;          // ImageType (0008,0008) [FrameType]
  std::string acquisition_number;  // AcquisitionNumber (0020,0012)
};

struct DicomSlice {
  // False for a DICOM file without pixel data (DICOMDIR, report, ...): the
  // fields below are then unset and a series reader skips the file.
  bool is_image = false;
  std::string series_uid;  // SeriesInstanceUID ("" if absent)
  // Identity, for listing the series of a folder ("" or 0 if absent).
  std::string series_description;  // SeriesDescription
  std::string modality;            // Modality: CT, MR, ...
  std::string sop_class_uid;       // SOPClassUID
  int64_t series_number = 0;       // SeriesNumber
  // Why this image must never be stacked into a volume ("localizer",
  // "secondary capture"); "" for an ordinary slice. When set, the geometry
  // and pixel fields below are not read.
  std::string not_a_slice_reason;
  DicomStackAttributes stack;  // read for every image
  int64_t rows = 0;        // j extent
  int64_t columns = 0;     // i extent
  // PixelSpacing as stored: [0] between rows (along j), [1] between columns
  // (along i), mm.
  std::array<double, 2> pixel_spacing_mm{0.0, 0.0};
  // ImageOrientationPatient: [0..2] the row direction (i axis), [3..5] the
  // column direction (j axis), LPS unit vectors.
  std::array<double, 6> orientation{};
  glm::dvec3 position_mm{0.0};      // ImagePositionPatient (LPS) of voxel (0,0)
  double slice_thickness_mm = 0.0;  // SliceThickness, 0 if absent
  std::vector<float> values;        // rows * columns, i fastest, after rescale
};

enum class DicomDecode {
  kHeaderOnly,  // identity and geometry only: `values` stays empty
  kPixels,      // also decode the pixel data
};

// True when `bytes` has the DICOM Part 10 preamble and "DICM" prefix.
bool LooksLikeDicom(std::span<const uint8_t> bytes);

// Parses one DICOM Part 10 file into its frames: one DicomSlice for a
// classic image, one per frame for an enhanced multi-frame CT/MR image
// (geometry and rescale from the per-frame, else shared, functional groups:
// PlanePositionSequence, PlaneOrientationSequence, PixelMeasuresSequence,
// PixelValueTransformationSequence). Values are stored * RescaleSlope +
// RescaleIntercept (Hounsfield units for CT). Handles BitsAllocated 8 and 16,
// signed and unsigned (PixelRepresentation), BitsStored / HighBit masking,
// uncompressed transfer syntaxes, and the RLE, JPEG and JPEG-LS ones through
// DCMTK's decoders. A file without pixel data gives one slice with is_image
// false. Errors (messages without the file name): InvalidArgument for
// malformed or truncated files or missing geometry attributes,
// ResourceExhausted for frames over `limits`, Unimplemented for valid files
// we do not read (colour, multi-frame without per-frame positions, 32-bit, a
// compressed transfer syntax without a decoder, deflate; the message names
// the syntax). Localizers (ImageType holds LOCALIZER) and secondary captures
// (their SOP classes) are returned with `not_a_slice_reason` set and neither
// geometry nor pixels.
Result<std::vector<DicomSlice>> ParseDicomFrames(std::span<const uint8_t> bytes,
                                                 const VolumeLimits& limits,
                                                 DicomDecode decode = DicomDecode::kPixels);

}  // namespace vpm

// Several stacks of images in one DICOM series: in several planes (a
// three-plane localizer, reformats), or at the same positions (multi-echo,
// dynamic and diffusion MR, Dixon), told apart by an attribute.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/io/read_dicom_slice.h"

namespace vpm {

// One image of a series (a classic file, or one frame of a multi-frame
// one), as the split sees it.
struct StackImage {
  DicomStackAttributes attributes;
  glm::dvec3 normal_lps{0.0, 0.0, 1.0};  // row x column direction
  glm::dvec3 position_mm{0.0};           // ImagePositionPatient, LPS
};

// A stack: its images (indices into the split's input, in input order) and
// what sets it apart, e.g. "EchoNumbers 2"; "" when the series is one stack.
struct DicomStack {
  std::string label;
  std::vector<size_t> images;
};

// Two images closer than this along the slice normal are at one position.
inline constexpr double kSamePositionMm = 0.01;

// Two images whose normals are closer than this (|cos| of the angle between
// them, 10 degrees) lie in one plane; further apart, in two (a three-plane
// localizer, a series of axial and coronal reformats). Within a plane the
// reader then holds the slices to one ImageOrientationPatient.
inline constexpr double kSamePlaneCos = 0.985;

// The stacks of a series. A series whose images lie in several planes, each
// of at least two images, is first split by plane, the plane with most
// images first, each labelled
// "axial", "coronal" or "sagittal" by its normal's largest component
// ("oblique axial" where that is under 0.95; "axial 2" for a second
// plane of that name); each plane is then split as a series is. A series
// whose images all lie at distinct
// positions along the first image's normal is one stack (every image,
// label ""). One that repeats positions is split by the first attribute, in
// the order EchoNumbers, EchoTime, TemporalPositionIdentifier, TriggerTime,
// DiffusionBValue, StackID, ImageType, AcquisitionNumber, whose values cut
// it into two or more stacks of at least two images each, none repeating a
// position; the stacks are ordered by that value (as numbers where every
// value is one; an absent value first). When no attribute does, the series
// is left as one stack (whose reading then fails on the repeated position).
std::vector<DicomStack> SplitDicomStacks(std::span<const StackImage> images);

}  // namespace vpm

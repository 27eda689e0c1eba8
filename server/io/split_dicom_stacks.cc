#include "server/io/split_dicom_stacks.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "server/common/status.h"
#include "server/io/header_text.h"

namespace vpm {
namespace {

struct SplitAttribute {
  const char* keyword;
  std::string DicomStackAttributes::*value;
};

// The order in which attributes are tried: the ones that name a stack
// (echo, phase, b-value) before the ones that only often differ.
constexpr SplitAttribute kSplitAttributes[] = {
    {"EchoNumbers", &DicomStackAttributes::echo_numbers},
    {"EchoTime", &DicomStackAttributes::echo_time},
    {"TemporalPositionIdentifier", &DicomStackAttributes::temporal_position},
    {"TriggerTime", &DicomStackAttributes::trigger_time},
    {"DiffusionBValue", &DicomStackAttributes::diffusion_b_value},
    {"StackID", &DicomStackAttributes::stack_id},
    {"ImageType", &DicomStackAttributes::image_type},
    {"AcquisitionNumber", &DicomStackAttributes::acquisition_number},
};

// Labels stay short whatever a file holds.
constexpr size_t kMaxValueChars = 64;

// True when two images of `chosen` lie within kSamePositionMm of each other
// along `normal`.
bool RepeatsAPosition(std::span<const StackImage> images, const std::vector<size_t>& chosen,
                      const glm::dvec3& normal) {
  std::vector<double> along;
  for (size_t n : chosen) along.push_back(glm::dot(images[n].position_mm, normal));
  std::sort(along.begin(), along.end());
  for (size_t n = 1; n < along.size(); ++n) {
    if (!(along[n] - along[n - 1] >= kSamePositionMm)) return true;  // NaN too
  }
  return false;
}

std::optional<double> FiniteNumber(const std::string& value) {
  const std::optional<double> x = ParseDouble(value);
  if (!x.has_value() || !std::isfinite(*x)) return std::nullopt;
  return x;
}

// Orders values as numbers where every one of them is a number, else as
// text; "" (absent) first either way.
bool ValueLess(const std::string& a, const std::string& b, bool numeric) {
  if (a.empty() || b.empty()) return !a.empty() < !b.empty();
  if (numeric) return *FiniteNumber(a) < *FiniteNumber(b);
  return a < b;
}

// The stacks `attribute` cuts the series into, when it does (see the header).
std::optional<std::vector<DicomStack>> SplitBy(std::span<const StackImage> images,
                                               const SplitAttribute& attribute,
                                               const glm::dvec3& normal) {
  std::map<std::string, std::vector<size_t>> groups;
  for (size_t n = 0; n < images.size(); ++n) {
    groups[images[n].attributes.*attribute.value].push_back(n);
  }
  if (groups.size() < 2) return std::nullopt;
  bool numeric = true;
  for (const auto& [value, members] : groups) {
    if (members.size() < 2 || RepeatsAPosition(images, members, normal)) {
      return std::nullopt;
    }
    numeric &= value.empty() || FiniteNumber(value).has_value();
  }
  std::vector<DicomStack> stacks;
  for (auto& [value, members] : groups) {
    // Numbers as 6 significant digits (a binary EffectiveEchoTime of 2.3
    // reads 2.2999999999999998 as text).
    const std::string shown = value.empty() ? "(none)"
                              : numeric     ? StrCat(*FiniteNumber(value))
                                            : value.substr(0, kMaxValueChars);
    stacks.push_back({StrCat(attribute.keyword, " ", shown), std::move(members)});
  }
  std::sort(stacks.begin(), stacks.end(), [&](const DicomStack& a, const DicomStack& b) {
    const auto value = [&](const DicomStack& s) -> const std::string& {
      return images[s.images.front()].attributes.*attribute.value;
    };
    return ValueLess(value(a), value(b), numeric);
  });
  return stacks;
}

// The series' images grouped by plane (normals within kSamePlaneCos of a
// group's first, either sign), the largest group first, ties in input
// order; each group's indices in input order.
std::vector<std::vector<size_t>> GroupByPlane(std::span<const StackImage> images) {
  std::vector<std::vector<size_t>> groups;
  for (size_t n = 0; n < images.size(); ++n) {
    auto same = std::find_if(groups.begin(), groups.end(), [&](const std::vector<size_t>& g) {
      return std::abs(glm::dot(images[g.front()].normal_lps, images[n].normal_lps)) >=
             kSamePlaneCos;
    });
    if (same == groups.end()) {
      groups.push_back({n});
    } else {
      same->push_back(n);
    }
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const auto& a, const auto& b) { return a.size() > b.size(); });
  return groups;
}

// "axial", "coronal" or "sagittal" by the normal's largest LPS component,
// "oblique ..." where that component is under 0.95; a name that repeats
// gets its count ("axial 2").
std::vector<std::string> PlaneLabels(std::span<const StackImage> images,
                                     const std::vector<std::vector<size_t>>& groups) {
  std::vector<std::string> labels;
  std::map<std::string, int> seen;
  for (const std::vector<size_t>& g : groups) {
    const glm::dvec3 a = glm::abs(images[g.front()].normal_lps);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    constexpr const char* kNames[] = {"sagittal", "coronal", "axial"};
    const std::string name = StrCat(a[axis] < 0.95 ? "oblique " : "", kNames[axis]);
    const int count = ++seen[name];
    labels.push_back(count == 1 ? name : StrCat(name, " ", count));
  }
  return labels;
}

// The stacks of images of one plane (see the header).
std::vector<DicomStack> SplitRepeats(std::span<const StackImage> images) {
  DicomStack whole;
  for (size_t n = 0; n < images.size(); ++n) whole.images.push_back(n);
  if (images.empty()) return {whole};
  const glm::dvec3 normal = images.front().normal_lps;
  if (!RepeatsAPosition(images, whole.images, normal)) return {whole};
  for (const SplitAttribute& attribute : kSplitAttributes) {
    if (std::optional<std::vector<DicomStack>> stacks = SplitBy(images, attribute, normal)) {
      return *std::move(stacks);
    }
  }
  return {whole};
}

}  // namespace

std::vector<DicomStack> SplitDicomStacks(std::span<const StackImage> images) {
  const std::vector<std::vector<size_t>> planes = GroupByPlane(images);
  // A plane of one image is no volume: such a series (radial slices, a
  // stray image) is left whole, and its reading says why it fails.
  const bool lone = std::any_of(planes.begin(), planes.end(),
                                [](const std::vector<size_t>& p) { return p.size() < 2; });
  if (planes.size() <= 1 || lone) return SplitRepeats(images);
  const std::vector<std::string> labels = PlaneLabels(images, planes);
  std::vector<DicomStack> out;
  for (size_t g = 0; g < planes.size(); ++g) {
    std::vector<StackImage> plane;
    for (size_t n : planes[g]) plane.push_back(images[n]);
    for (const DicomStack& stack : SplitRepeats(plane)) {
      DicomStack mapped{stack.label.empty() ? labels[g] : StrCat(labels[g], ", ", stack.label), {}};
      for (size_t n : stack.images) mapped.images.push_back(planes[g][n]);
      out.push_back(std::move(mapped));
    }
  }
  return out;
}

}  // namespace vpm

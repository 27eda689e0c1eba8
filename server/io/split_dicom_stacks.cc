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
    {"ImageType", &DicomStackAttributes::image_type},
    {"AcquisitionNumber", &DicomStackAttributes::acquisition_number},
};

// Labels stay short whatever a file holds.
constexpr size_t kMaxValueChars = 64;

int64_t ImageCount(std::span<const StackFile> files, const std::vector<size_t>& chosen) {
  int64_t images = 0;
  for (size_t f : chosen) images += static_cast<int64_t>(files[f].positions_mm.size());
  return images;
}

// True when two images of `chosen` lie within kSamePositionMm of each other
// along `normal`.
bool RepeatsAPosition(std::span<const StackFile> files, const std::vector<size_t>& chosen,
                      const glm::dvec3& normal) {
  std::vector<double> along;
  for (size_t f : chosen) {
    for (const glm::dvec3& p : files[f].positions_mm) along.push_back(glm::dot(p, normal));
  }
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
std::optional<std::vector<DicomStack>> SplitBy(std::span<const StackFile> files,
                                               const SplitAttribute& attribute,
                                               const glm::dvec3& normal) {
  std::map<std::string, std::vector<size_t>> groups;
  for (size_t f = 0; f < files.size(); ++f) {
    groups[files[f].attributes.*attribute.value].push_back(f);
  }
  if (groups.size() < 2) return std::nullopt;
  bool numeric = true;
  for (const auto& [value, members] : groups) {
    if (ImageCount(files, members) < 2 || RepeatsAPosition(files, members, normal)) {
      return std::nullopt;
    }
    numeric &= value.empty() || FiniteNumber(value).has_value();
  }
  std::vector<DicomStack> stacks;
  for (auto& [value, members] : groups) {
    const std::string shown = value.empty() ? "(none)" : value.substr(0, kMaxValueChars);
    stacks.push_back({StrCat(attribute.keyword, " ", shown), std::move(members)});
  }
  std::sort(stacks.begin(), stacks.end(), [&](const DicomStack& a, const DicomStack& b) {
    const auto value = [&](const DicomStack& s) -> const std::string& {
      return files[s.files.front()].attributes.*attribute.value;
    };
    return ValueLess(value(a), value(b), numeric);
  });
  return stacks;
}

}  // namespace

std::vector<DicomStack> SplitDicomStacks(std::span<const StackFile> files) {
  DicomStack whole;
  for (size_t f = 0; f < files.size(); ++f) whole.files.push_back(f);
  if (files.empty()) return {whole};
  const glm::dvec3 normal = files.front().normal_lps;
  if (!RepeatsAPosition(files, whole.files, normal)) return {whole};
  for (const SplitAttribute& attribute : kSplitAttributes) {
    if (std::optional<std::vector<DicomStack>> stacks = SplitBy(files, attribute, normal)) {
      return *std::move(stacks);
    }
  }
  return {whole};
}

}  // namespace vpm

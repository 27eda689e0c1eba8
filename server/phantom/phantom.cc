#include "server/phantom/phantom.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "absl/strings/numbers.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "server/phantom/phantom_abdomen.h"

namespace vpm {
namespace {

struct PhantomEntry {
  const char* name;
  Result<Volume> (*make)(const PhantomSpec&, const VolumeLimits&);
};
constexpr PhantomEntry kPhantoms[] = {{"abdomen", phantom::MakeAbdomenPhantom}};

constexpr const char* kValidParameters =
    "valid parameters: size=N, dims=X,Y,Z, spacing=A,B,C (mm), seed=S, noise=SIGMA (HU)";

const PhantomEntry* FindPhantom(absl::string_view name) {
  for (const PhantomEntry& entry : kPhantoms) {
    if (name == entry.name) return &entry;
  }
  return nullptr;
}

Status BadValue(absl::string_view key, absl::string_view value, absl::string_view expected) {
  return absl::InvalidArgumentError(StrCat("phantom parameter '", key, "' is '", value,
                                                 "'; it must be ", expected, " (", kValidParameters,
                                                 ")"));
}

Result<int64_t> ParseVoxelCount(absl::string_view key, absl::string_view text) {
  int64_t n = 0;
  if (!absl::SimpleAtoi(text, &n) || n <= 0) return BadValue(key, text, "a positive integer");
  return n;
}

Result<std::array<int64_t, 3>> ParseDims(absl::string_view text) {
  const std::vector<absl::string_view> parts = absl::StrSplit(text, ',');
  constexpr const char* kExpected = "three positive integers X,Y,Z";
  if (parts.size() != 3) return BadValue("dims", text, kExpected);
  std::array<int64_t, 3> dims{};
  for (size_t a = 0; a < 3; ++a) {
    if (!absl::SimpleAtoi(parts[a], &dims[a]) || dims[a] <= 0) {
      return BadValue("dims", text, kExpected);
    }
  }
  return dims;
}

// Spacing and noise outside these ranges are mistakes, and would push the
// float arithmetic of the rasterizer towards overflow.
constexpr double kMinSpacingMm = 1e-3;
constexpr double kMaxSpacingMm = 1e3;
constexpr double kMaxNoiseHu = 1e4;

Result<glm::dvec3> ParseSpacing(absl::string_view text) {
  const std::vector<absl::string_view> parts = absl::StrSplit(text, ',');
  constexpr const char* kExpected = "three numbers A,B,C from 0.001 to 1000 (mm)";
  if (parts.size() != 3) return BadValue("spacing", text, kExpected);
  glm::dvec3 spacing(0.0);
  for (int a = 0; a < 3; ++a) {
    // NaN fails both comparisons.
    if (!absl::SimpleAtod(parts[static_cast<size_t>(a)], &spacing[a]) ||
        !(spacing[a] >= kMinSpacingMm && spacing[a] <= kMaxSpacingMm)) {
      return BadValue("spacing", text, kExpected);
    }
  }
  return spacing;
}

// Applies one "key=value" parameter to `spec`.
Status ApplyParameter(absl::string_view key, absl::string_view value, PhantomSpec& spec) {
  if (key == "size") {
    ASSIGN_OR_RETURN(const int64_t n, ParseVoxelCount(key, value));
    spec.dims = {n, n, n};
  } else if (key == "dims") {
    ASSIGN_OR_RETURN(spec.dims, ParseDims(value));
  } else if (key == "spacing") {
    ASSIGN_OR_RETURN(spec.spacing_mm, ParseSpacing(value));
  } else if (key == "seed") {
    if (!absl::SimpleAtoi(value, &spec.seed)) {
      return BadValue(key, value, "an unsigned 64-bit integer");
    }
  } else if (key == "noise") {
    if (!absl::SimpleAtod(value, &spec.noise_sigma_hu) ||
        !(spec.noise_sigma_hu >= 0.0 && spec.noise_sigma_hu <= kMaxNoiseHu)) {
      return BadValue(key, value, "a number from 0 to 10000 (HU)");
    }
  } else {
    return absl::InvalidArgumentError(
        StrCat("unknown phantom parameter '", key, "'; ", kValidParameters));
  }
  return absl::OkStatus();
}

std::string FormatSpec(const PhantomSpec& spec) {
  std::string text = StrCat(spec.name, "?dims=", absl::StrJoin(spec.dims, ","));
  if (spec.spacing_mm) {
    StrAppend(&text, "&spacing=", spec.spacing_mm->x, ",", spec.spacing_mm->y, ",",
                    spec.spacing_mm->z);
  }
  StrAppend(&text, "&seed=", spec.seed, "&noise=", spec.noise_sigma_hu);
  return text;
}

}  // namespace

std::vector<std::string> PhantomNames() {
  std::vector<std::string> names;
  for (const PhantomEntry& entry : kPhantoms) names.emplace_back(entry.name);
  std::sort(names.begin(), names.end());
  return names;
}

Result<PhantomSpec> ParsePhantomSpec(std::string_view spec_text) {
  // Debian's Abseil has its own string_view type.
  const absl::string_view text(spec_text.data(), spec_text.size());
  const size_t question = text.find('?');
  PhantomSpec spec;
  spec.name = std::string(text.substr(0, question));
  if (FindPhantom(spec.name) == nullptr) {
    return absl::InvalidArgumentError(
        StrCat("unknown phantom '", spec.name,
                     "'; valid phantoms: ", absl::StrJoin(PhantomNames(), ", ")));
  }
  if (question == absl::string_view::npos || question + 1 == text.size()) return spec;
  std::set<absl::string_view> seen;
  for (absl::string_view parameter : absl::StrSplit(text.substr(question + 1), '&')) {
    const size_t equals = parameter.find('=');
    const absl::string_view key = parameter.substr(0, equals);
    if (equals == absl::string_view::npos || equals + 1 == parameter.size()) {
      return absl::InvalidArgumentError(
          StrCat("phantom parameter '", parameter, "' has no value; ", kValidParameters));
    }
    if (!seen.insert(key).second) {
      return absl::InvalidArgumentError(
          StrCat("phantom parameter '", key, "' is given twice; ", kValidParameters));
    }
    RETURN_IF_ERROR(ApplyParameter(key, parameter.substr(equals + 1), spec));
  }
  if (seen.count("size") && seen.count("dims")) {
    return absl::InvalidArgumentError(
        "phantom parameters 'size' and 'dims' both set the voxel count; give one");
  }
  return spec;
}

Result<Volume> MakePhantomFromSpec(const PhantomSpec& spec, const VolumeLimits& limits) {
  const PhantomEntry* entry = FindPhantom(spec.name);
  if (entry == nullptr) {
    return absl::InvalidArgumentError(
        StrCat("unknown phantom '", spec.name,
                     "'; valid phantoms: ", absl::StrJoin(PhantomNames(), ", ")));
  }
  // A spec built in code skips the parser's range checks.
  if (!(spec.noise_sigma_hu >= 0.0 && spec.noise_sigma_hu <= kMaxNoiseHu)) {
    return absl::InvalidArgumentError(
        StrCat("phantom noise ", spec.noise_sigma_hu, " HU is outside 0 to 10000 HU"));
  }
  if (spec.spacing_mm &&
      !(glm::all(glm::greaterThanEqual(*spec.spacing_mm, glm::dvec3(kMinSpacingMm))) &&
        glm::all(glm::lessThanEqual(*spec.spacing_mm, glm::dvec3(kMaxSpacingMm))))) {
    return absl::InvalidArgumentError("phantom spacing is outside 0.001 to 1000 mm");
  }
  ASSIGN_OR_RETURN(Volume volume, entry->make(spec, limits));
  volume.set_source(StrCat("phantom:", FormatSpec(spec)));
  return volume;
}

Result<Volume> MakePhantom(std::string_view spec_text, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const PhantomSpec spec, ParsePhantomSpec(spec_text));
  ASSIGN_OR_RETURN(Volume volume, MakePhantomFromSpec(spec, limits));
  volume.set_source(StrCat("phantom:", std::string(spec_text)));
  return volume;
}

}  // namespace vpm

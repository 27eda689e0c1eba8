#include "server/io/read_paraview_preset.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

#include "server/io/header_text.h"
#include "server/io/read_file_bytes.h"

namespace vpm {
namespace {

using nlohmann::json;

constexpr int kCurveSamples = 16;  // sub-points per non-linear opacity segment

// The numbers of key `key` of `entry`, a flat array whose length is a
// multiple of `stride`.
Result<std::vector<double>> FlatNumbers(const json& entry, const char* key, size_t stride,
                                        std::string_view what) {
  const auto it = entry.find(key);
  if (it == entry.end()) return absl::InvalidArgumentError(StrCat(what, ": no \"", key, "\""));
  if (!it->is_array() || it->empty() || it->size() % stride != 0) {
    return absl::InvalidArgumentError(StrCat(what, ": \"", key, "\" must be a non-empty array of ",
                                             stride, " numbers per point"));
  }
  if (it->size() / stride > kMaxRenderTfPoints) {
    return absl::InvalidArgumentError(StrCat(what, ": \"", key, "\" holds ", it->size() / stride,
                                             " points; at most ", kMaxRenderTfPoints));
  }
  std::vector<double> out;
  out.reserve(it->size());
  for (size_t i = 0; i < it->size(); ++i) {
    const json& v = (*it)[i];
    // JSON has no NaN: ParaView writes none, and a null or a string here is
    // as malformed as a NaN would be.
    if (!v.is_number()) {
      return absl::InvalidArgumentError(
          StrCat(what, ": \"", key, "\" item ", i, " is not a number"));
    }
    out.push_back(v.get<double>());
  }
  return out;
}

// vtkPiecewiseFunction's curve between (0, y1) and (1, y2) at x in [0, 1]
// for a segment's midpoint and sharpness (both in [0, 1]).
double VtkSegmentCurve(double x, double y1, double y2, double midpoint, double sharpness) {
  const double m = std::clamp(midpoint, 1e-5, 1.0 - 1e-5);
  x = x < m ? 0.5 * x / m : 0.5 + 0.5 * (x - m) / (1.0 - m);
  if (sharpness < 0.01) return (1.0 - x) * y1 + x * y2;
  if (x < 0.5) {
    x = 0.5 * std::pow(x * 2.0, 1.0 + 10.0 * sharpness);
  } else if (x > 0.5) {
    x = 1.0 - 0.5 * std::pow((1.0 - x) * 2.0, 1.0 + 10.0 * sharpness);
  }
  const double xx = x * x, xxx = xx * x;
  const double h1 = 2 * xxx - 3 * xx + 1, h2 = -2 * xxx + 3 * xx;
  const double h3 = xxx - 2 * xx + x, h4 = xxx - xx;
  const double t = (1.0 - sharpness) * (y2 - y1);
  const double v = h1 * y1 + h2 * y2 + h3 * t + h4 * t;
  return std::clamp(v, std::min(y1, y2), std::max(y1, y2));
}

// Opacity points from "Points" [x, alpha, midpoint, sharpness, ...]: linear
// segments as they are, the others sampled (sharpness > 0.99: a step at the
// midpoint).
Result<std::vector<TfOpacityPoint>> OpacityPoints(const std::vector<double>& p,
                                                  std::string_view what) {
  std::vector<TfOpacityPoint> out;
  const size_t n = p.size() / 4;
  for (size_t i = 0; i < n; ++i) {
    const double x1 = p[4 * i], y1 = p[4 * i + 1], mid = p[4 * i + 2], sharp = p[4 * i + 3];
    if (!(mid >= 0.0 && mid <= 1.0) || !(sharp >= 0.0 && sharp <= 1.0)) {
      return absl::InvalidArgumentError(StrCat(
          what, ": \"Points\" point ", i, ": midpoint and sharpness must be in [0, 1]"));
    }
    out.push_back({x1, y1});
    if (i + 1 == n || (mid == 0.5 && sharp == 0.0)) continue;
    const double x2 = p[4 * (i + 1)], y2 = p[4 * (i + 1) + 1];
    if (!(x2 > x1)) continue;  // unsorted or a step: validation names it
    if (sharp > 0.99) {
      const double xm = x1 + mid * (x2 - x1);
      out.push_back({xm, y1});
      out.push_back({xm, y2});
      continue;
    }
    for (int s = 1; s < kCurveSamples; ++s) {
      const double f = double(s) / kCurveSamples;
      out.push_back({x1 + f * (x2 - x1), VtkSegmentCurve(f, y1, y2, mid, sharp)});
    }
  }
  return out;
}

// The entry named `name` ("": the first) of the parsed file.
Result<const json*> FindEntry(const json& root, std::string_view name, std::string_view what) {
  if (!root.is_array() && !root.is_object()) {
    return absl::InvalidArgumentError(StrCat(what, ": expected a JSON array of presets"));
  }
  const json* found = nullptr;
  std::string names;
  const size_t count = root.is_array() ? root.size() : 1;
  for (size_t i = 0; i < count && found == nullptr; ++i) {
    const json& entry = root.is_array() ? root[i] : root;
    if (!entry.is_object()) {
      return absl::InvalidArgumentError(StrCat(what, ": preset ", i, " is not a JSON object"));
    }
    const auto it = entry.find("Name");
    const std::string entry_name = it != entry.end() && it->is_string() ? it->get<std::string>() : "";
    if (name.empty() || entry_name == name) found = &entry;
    if (names.size() < 400) {
      names += StrCat(names.empty() ? "" : ", ", QuoteForMessage(entry_name, '\''));
    }
  }
  if (found != nullptr) return found;
  if (count == 0) return absl::InvalidArgumentError(StrCat(what, ": the preset list is empty"));
  return absl::InvalidArgumentError(
      StrCat(what, ": no preset named ", QuoteForMessage(name, '\''), "; the file holds ", names));
}

}  // namespace

Result<RenderTransferFunction> ParseParaviewPreset(std::string_view text, std::string_view name,
                                                   std::string_view what) {
  const json root = json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) return absl::InvalidArgumentError(StrCat(what, ": not valid JSON"));
  ASSIGN_OR_RETURN(const json* entry, FindEntry(root, name, what));
  RenderTransferFunction tf;
  if (const auto it = entry->find("Name"); it != entry->end() && it->is_string()) {
    tf.name = it->get<std::string>();
  }
  const std::string where =
      tf.name.empty() ? std::string(what) : StrCat(what, " ", QuoteForMessage(tf.name, '\''));
  ASSIGN_OR_RETURN(const std::vector<double> rgb, FlatNumbers(*entry, "RGBPoints", 4, where));
  for (size_t i = 0; i < rgb.size(); i += 4) {
    tf.colors.push_back({rgb[i], glm::dvec3(rgb[i + 1], rgb[i + 2], rgb[i + 3])});
  }
  if (entry->contains("Points")) {
    ASSIGN_OR_RETURN(const std::vector<double> points, FlatNumbers(*entry, "Points", 4, where));
    ASSIGN_OR_RETURN(tf.opacities, OpacityPoints(points, where));
  } else {
    tf.opacities = {{tf.colors.front().value, 0.0}, {tf.colors.back().value, 1.0}};
  }
  if (tf.opacities.size() > kMaxRenderTfPoints) {
    return absl::InvalidArgumentError(StrCat(where, ": the opacity curves make ",
                                             tf.opacities.size(), " points; at most ",
                                             kMaxRenderTfPoints));
  }
  RETURN_IF_ERROR(ValidateRenderTransferFunction(tf, where));
  return tf;
}

Result<RenderTransferFunction> ReadParaviewPreset(const std::string& path, std::string_view name) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes,
                   ReadFileBytes(path, VolumeLimits{.max_bytes = kMaxRenderTfFileBytes}));
  return ParseParaviewPreset(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), name, path);
}

}  // namespace vpm

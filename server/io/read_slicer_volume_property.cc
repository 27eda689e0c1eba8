#include "server/io/read_slicer_volume_property.h"

#include <charconv>
#include <cmath>
#include <filesystem>

#include "server/io/header_text.h"
#include "server/io/read_file_bytes.h"

namespace vpm {
namespace {

constexpr std::string_view kSpace = " \t\r\n";

// The whitespace-separated words of `line`.
std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = line.find_first_not_of(kSpace);
  while (i != std::string_view::npos) {
    const size_t end = std::min(line.find_first_of(kSpace, i), line.size());
    words.push_back(line.substr(i, end - i));
    i = line.find_first_not_of(kSpace, end);
  }
  return words;
}

Result<double> Number(std::string_view word, std::string_view what) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v)) {
    return absl::InvalidArgumentError(
        StrCat(what, ": ", QuoteForMessage(word, '\''), " is not a finite number"));
  }
  return v;
}

// The nine lines of the file (a missing one is an error naming it).
Result<std::vector<std::string_view>> Lines(std::string_view text, std::string_view what) {
  std::vector<std::string_view> lines;
  while (!text.empty() && lines.size() < 9) {
    const size_t end = std::min(text.find('\n'), text.size());
    lines.push_back(text.substr(0, end));
    text.remove_prefix(std::min(end + 1, text.size()));
  }
  if (lines.size() < 9) {
    return absl::InvalidArgumentError(StrCat(what, ": ", lines.size(),
                                             " lines; a Slicer volume property has 9"));
  }
  return lines;
}

}  // namespace

Result<std::vector<double>> ParseSlicerFunctionString(std::string_view line, int stride,
                                                      std::string_view what) {
  const std::vector<std::string_view> words = Words(line);
  if (words.empty()) return absl::InvalidArgumentError(StrCat(what, ": empty"));
  ASSIGN_OR_RETURN(const double count, Number(words[0], what));
  if (count != std::floor(count) || count < stride || std::fmod(count, stride) != 0.0) {
    return absl::InvalidArgumentError(StrCat(what, ": count ", count,
                                             " must be a positive multiple of ", stride));
  }
  if (count / stride > double(kMaxRenderTfPoints)) {
    return absl::InvalidArgumentError(StrCat(what, ": ", count / stride, " points; at most ",
                                             kMaxRenderTfPoints));
  }
  if (double(words.size() - 1) != count) {
    return absl::InvalidArgumentError(
        StrCat(what, ": count says ", count, " numbers, the line holds ", words.size() - 1));
  }
  std::vector<double> out;
  out.reserve(words.size() - 1);
  for (size_t i = 1; i < words.size(); ++i) {
    ASSIGN_OR_RETURN(const double v, Number(words[i], what));
    out.push_back(v);
  }
  return out;
}

Result<RenderTransferFunction> ParseSlicerVolumeProperty(std::string_view text,
                                                         std::string_view name,
                                                         std::string_view what) {
  ASSIGN_OR_RETURN(const std::vector<std::string_view> lines, Lines(text, what));
  double scalars[6];
  const char* scalar_names[6] = {"interpolation", "shade",    "diffuse",
                                 "ambient",       "specular", "specular power"};
  for (int i = 0; i < 6; ++i) {
    const std::vector<std::string_view> words = Words(lines[i]);
    const std::string line_what = StrCat(what, " line ", i + 1, " (", scalar_names[i], ")");
    if (words.size() != 1) {
      return absl::InvalidArgumentError(StrCat(line_what, ": expected one number"));
    }
    ASSIGN_OR_RETURN(scalars[i], Number(words[0], line_what));
  }
  RenderTransferFunction tf;
  tf.name = std::string(name);
  tf.lighting = TfLighting{scalars[1] != 0.0, scalars[3], scalars[2], scalars[4], scalars[5]};
  ASSIGN_OR_RETURN(const std::vector<double> opacity,
                   ParseSlicerFunctionString(lines[6], 2, StrCat(what, " line 7 (scalar opacity)")));
  // Checked for form only: vpm does not apply the gradient opacity.
  RETURN_IF_ERROR(
      ParseSlicerFunctionString(lines[7], 2, StrCat(what, " line 8 (gradient opacity)")).status());
  ASSIGN_OR_RETURN(const std::vector<double> color,
                   ParseSlicerFunctionString(lines[8], 4, StrCat(what, " line 9 (colour)")));
  for (size_t i = 0; i < opacity.size(); i += 2) tf.opacities.push_back({opacity[i], opacity[i + 1]});
  for (size_t i = 0; i < color.size(); i += 4) {
    tf.colors.push_back({color[i], glm::dvec3(color[i + 1], color[i + 2], color[i + 3])});
  }
  RETURN_IF_ERROR(ValidateRenderTransferFunction(tf, what));
  return tf;
}

Result<RenderTransferFunction> ReadSlicerVolumeProperty(const std::string& path) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes,
                   ReadFileBytes(path, VolumeLimits{.max_bytes = kMaxRenderTfFileBytes}));
  return ParseSlicerVolumeProperty(
      std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
      std::filesystem::path(path).stem().string(), path);
}

}  // namespace vpm

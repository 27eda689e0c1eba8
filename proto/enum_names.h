// The API's enums by the names the CLI flags, interaction scripts, the web
// page and the JSON outputs use ("dvr", "png", "point", "spread",
// "lattice"), shared by the server and the clients. FromName returns nullopt
// for a name it does not know; VertexKindName gives "unknown" for a value
// outside the enum.
#pragma once

#include <optional>
#include <string_view>

#include "vpm/v3/vpm.pb.h"

namespace vpm {

inline std::optional<v3::RenderMode> RenderModeFromName(std::string_view name) {
  if (name == "dvr") return v3::RENDER_MODE_DVR;
  if (name == "mip") return v3::RENDER_MODE_MIP;
  return std::nullopt;
}

inline std::optional<v3::Encoding> EncodingFromName(std::string_view name) {
  if (name == "jpeg") return v3::ENCODING_JPEG;
  if (name == "png") return v3::ENCODING_PNG;
  return std::nullopt;
}

// RenderSettings.interactive_quality: "auto" (UNSPECIFIED: the server's
// device chooses, sharp on a discrete GPU, else fast), "fast", "balanced",
// "sharp".
inline std::optional<v3::InteractiveQuality> InteractiveQualityFromName(std::string_view name) {
  if (name == "auto") return v3::INTERACTIVE_QUALITY_UNSPECIFIED;
  if (name == "fast") return v3::INTERACTIVE_QUALITY_FAST;
  if (name == "balanced") return v3::INTERACTIVE_QUALITY_BALANCED;
  if (name == "sharp") return v3::INTERACTIVE_QUALITY_SHARP;
  return std::nullopt;
}

// "auto" (UNSPECIFIED), "fast", "balanced", "sharp"; "unknown" outside the
// enum.
inline std::string_view InteractiveQualityName(v3::InteractiveQuality quality) {
  switch (quality) {
    case v3::INTERACTIVE_QUALITY_UNSPECIFIED:
      return "auto";
    case v3::INTERACTIVE_QUALITY_FAST: return "fast";
    case v3::INTERACTIVE_QUALITY_BALANCED: return "balanced";
    case v3::INTERACTIVE_QUALITY_SHARP: return "sharp";
    default:
      return "unknown";
  }
}

// A frame file's encoding from its name: .png is PNG, anything else JPEG.
inline v3::Encoding EncodingForFile(std::string_view file_name) {
  return file_name.ends_with(".png") ? v3::ENCODING_PNG : v3::ENCODING_JPEG;
}

inline std::string_view EncodingExtension(v3::Encoding encoding) {
  return encoding == v3::ENCODING_PNG ? "png" : "jpg";
}

inline std::optional<v3::Footprint> FootprintFromName(std::string_view name) {
  if (name == "point") return v3::FOOTPRINT_POINT;
  if (name == "cell") return v3::FOOTPRINT_CELL;
  return std::nullopt;
}

inline std::optional<v3::DensityMode> DensityModeFromName(std::string_view name) {
  if (name == "spread") return v3::DENSITY_MODE_SPREAD;
  if (name == "paper") return v3::DENSITY_MODE_PAPER;
  return std::nullopt;
}

inline std::string_view VertexKindName(v3::VertexKind kind) {
  switch (kind) {
    case v3::VERTEX_KIND_LATTICE: return "lattice";
    case v3::VERTEX_KIND_ANCHOR: return "anchor";
    case v3::VERTEX_KIND_REFINED: return "refined";
    default: return "unknown";
  }
}

}  // namespace vpm

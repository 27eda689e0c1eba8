#include "server/io/read_render_transfer_function.h"

#include <string>

#include "server/io/read_paraview_preset.h"
#include "server/io/read_slicer_volume_property.h"

namespace vpm {

Result<RenderTransferFunction> ReadRenderTransferFunction(std::string_view spec) {
  const size_t hash = spec.rfind('#');
  const std::string path(spec.substr(0, hash));
  const std::string_view name = hash == std::string_view::npos ? "" : spec.substr(hash + 1);
  if (path.ends_with(".vp.json")) {
    return absl::InvalidArgumentError(StrCat(
        path, ": Slicer's JSON volume property is not read; save it as .vp (Slicer's text form)"));
  }
  if (path.ends_with(".json")) return ReadParaviewPreset(path, name);
  if (path.ends_with(".vp") || path.ends_with(".txt")) {
    if (hash != std::string_view::npos) {
      return absl::InvalidArgumentError(
          StrCat(spec, ": '#NAME' picks a ParaView preset; a Slicer .vp holds one property"));
    }
    return ReadSlicerVolumeProperty(path);
  }
  return absl::InvalidArgumentError(
      StrCat(spec, ": a transfer function file is FILE.json[#NAME] (ParaView preset) or "
                   "FILE.vp (3D Slicer volume property)"));
}

}  // namespace vpm

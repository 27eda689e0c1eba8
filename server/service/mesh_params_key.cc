#include "server/service/mesh_params_key.h"

#include <sstream>

namespace vpm::service {

std::optional<std::string> MeshParamsKey(std::string_view volume_id, const MeshParams& p) {
  if (!p.classify.overrides.empty()) return std::nullopt;
  std::ostringstream key;
  key << std::hexfloat;
  key << volume_id << "|grid " << p.grid[0] << ' ' << p.grid[1] << ' ' << p.grid[2]
      << "|target " << p.target << "|footprint " << static_cast<int>(p.footprint)
      << "|density " << static_cast<int>(p.density_mode) << "|wg " << p.wg << "|wd " << p.wd
      << "|R " << p.radius_factor << "|tf " << p.tf << "|bone " << p.classify.bone_threshold
      << "|influence " << p.classify.influence_threshold << ' ' << p.classify.influence_factor
      << "|roi " << p.roi_radius_factor << "|refine_count " << p.refine_count;
  if (p.refine_at_mm) {
    key << "|refine_at " << p.refine_at_mm->x << ' ' << p.refine_at_mm->y << ' '
        << p.refine_at_mm->z;
  }
  return key.str();
}

}  // namespace vpm::service

// VertexKindName of proxy_mesh.h. It lives in vpm_tetmesh, the lowest mesh
// library, because the mesh files (mesh_json, write_vtu) need it.
#include "server/mesh/proxy_mesh.h"

namespace vpm {

const char* VertexKindName(VertexKind kind) {
  switch (kind) {
    case VertexKind::kLattice:
      return "lattice";
    case VertexKind::kAnchor:
      return "anchor";
    case VertexKind::kRefined:
      return "refined";
  }
  return "unknown";
}

}  // namespace vpm

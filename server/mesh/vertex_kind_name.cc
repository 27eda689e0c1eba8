// VertexKindName of proxy_mesh.h: the names the mesh files (mesh_json,
// write_vtu) and the service write.
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
    case VertexKind::kBoundary:
      return "boundary";
    case VertexKind::kSteiner:
      return "steiner";
  }
  return "unknown";
}

}  // namespace vpm

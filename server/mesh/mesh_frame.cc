#include "server/mesh/mesh_frame.h"

#include <utility>

namespace vpm {
namespace {

template <typename Map>
ProxyMesh Mapped(const ProxyMesh& mesh, const VolumeGeometry& geometry, Map map) {
  ProxyMesh out = mesh;
  for (MeshVertex& v : out.vertices) v.position_mm = map(v.position_mm);
  if (glm::determinant(geometry.direction) < 0.0) {
    for (auto& t : out.tets) std::swap(t[2], t[3]);
  }
  return out;
}

}  // namespace

ProxyMesh MeshToWorld(const ProxyMesh& mesh, const VolumeGeometry& geometry) {
  return Mapped(mesh, geometry, [&](const glm::dvec3& p) { return geometry.PhysicalToWorld(p); });
}

ProxyMesh MeshFromWorld(const ProxyMesh& mesh, const VolumeGeometry& geometry) {
  return Mapped(mesh, geometry, [&](const glm::dvec3& p) { return geometry.WorldToPhysical(p); });
}

}  // namespace vpm

// The pinned phantom mesh of the forced-drag tests (tests/data/meshes/
// README.md): the unrefined 250-vertex cell mesh of phantom:abdomen (256^3),
// as it was built before sliver removal, where a drag at the left renal
// artery locks against hard vertices and ends forced.
#pragma once

#include <cstdlib>
#include <string>

#include <gtest/gtest.h>
#include <glm/glm.hpp>

#include "server/mesh/mesh_json.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm::testing {

// left_renal_artery of phantom:abdomen (`vpm volume info phantom:abdomen`), mm.
inline const glm::dvec3 kPinnedGrabMm(233.47, 217.07, 130.93);

// The mesh, or an empty one (with a test failure) when it cannot be read.
inline ProxyMesh PinnedPhantomMesh() {
  const char* root = std::getenv("VPM_SOURCE_DIR");
  const std::string path =
      std::string(root ? root : ".") + "/tests/data/meshes/phantom-abdomen-cell-250.json";
  auto mesh = ReadMeshJson(path);
  EXPECT_TRUE(mesh.ok()) << mesh.status();
  return mesh.ok() ? *std::move(mesh) : ProxyMesh{};
}

// The largest vertex coordinates (the volume's extent for this mesh), mm.
inline glm::dvec3 BoxExtent(const ProxyMesh& mesh) {
  glm::dvec3 extent(0.0);
  for (const MeshVertex& v : mesh.vertices) extent = glm::max(extent, v.position_mm);
  return extent;
}

}  // namespace vpm::testing

// Translations between the wire types (vpm/v3/vpm.proto) and the compute
// core's, with the checks that name the offending field.
#pragma once

#include <string>
#include <string_view>

#include "proto/vec3_convert.h"
#include "server/common/status.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/scene/deformable_scene.h"
#include "server/service/mesh_store.h"
#include "server/service/slice_request.h"
#include "server/service/volume_store.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

// The API's points, offsets and forces are world LPS mm (vpm.v3); the
// compute core's are physical voxel space (server/volume/volume.h). These
// convert at the boundary, for one volume's geometry.
glm::dvec3 PointFromApi(const v3::Vec3& world_mm, const VolumeGeometry& geometry);
glm::dvec3 VectorFromApi(const v3::Vec3& world, const VolumeGeometry& geometry);
v3::Vec3 PointToApi(const glm::dvec3& physical_mm, const VolumeGeometry& geometry);

void FillVolumeInfo(const VolumeEntry& entry, v3::VolumeInfo* info);
void FillMeshInfo(const MeshEntry& entry, v3::MeshInfo* info);
// Vertex positions in world LPS mm.
void FillMeshGeometry(const ProxyMesh& mesh, const VolumeGeometry& geometry,
                      v3::GetMeshResponse* response);

// Unset fields take the docs/ALGORITHM.md defaults. InvalidArgument names the field.
// refine_at_mm (world) comes back in `geometry`'s physical voxel space.
Result<MeshParams> ToMeshParams(const v3::MeshParams& params, const VolumeGeometry& geometry);
// The inverse (every field set; refine_at in world LPS): what a case keeps.
v3::MeshParams MeshParamsToApi(const MeshParams& params, const VolumeGeometry& geometry);

// How one stream wants its frames: the scene view but for the camera, plus
// the encoding.
struct StreamSettings {
  SceneView view;  // camera filled in per frame
  bool png = false;
  int jpeg_quality = 85;
  std::vector<SliceRequest> slices;  // RenderSettings.slices: with every frame
};
// InvalidArgument names the field ("settings.width: ..."); max_side caps
// width and height.
Result<StreamSettings> ToStreamSettings(const v3::RenderSettings& settings, const Volume& volume,
                                        int max_side);

// A frame's encoding from the wire's fields: InvalidArgument naming
// `prefix` + "encoding" or "jpeg_quality" (0: 85).
struct FrameEncoding {
  bool png = false;
  int jpeg_quality = 85;
};
Result<FrameEncoding> ToFrameEncoding(v3::Encoding encoding, int32_t jpeg_quality,
                                      std::string_view prefix);

// RenderSettings.slices (at most kMaxSlicesPerFrame, each view tag once),
// appended to `out`.
Status ToSliceRequests(const v3::RenderSettings& settings, const Volume& volume, int max_side,
                       std::vector<SliceRequest>* out);

// The absolute pose of `camera` on `volume`'s default camera.
Result<Camera> ToCamera(const v3::Camera& camera, const VolumeGeometry& geometry);
v3::Camera FromCamera(const Camera& camera);

}  // namespace vpm::service

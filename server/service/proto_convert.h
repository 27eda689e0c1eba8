// Translations between the wire types (vpm/v2/vpm.proto) and the compute
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
#include "vpm/v2/vpm.pb.h"

namespace vpm::service {

void FillVolumeInfo(const VolumeEntry& entry, v2::VolumeInfo* info);
void FillMeshInfo(const MeshEntry& entry, v2::MeshInfo* info);
void FillMeshGeometry(const ProxyMesh& mesh, v2::GetMeshResponse* response);

// Unset fields take the docs/ALGORITHM.md defaults. InvalidArgument names the field.
Result<MeshParams> ToMeshParams(const v2::MeshParams& params);

// How one stream wants its frames: the scene view but for the camera, plus
// the encoding.
struct StreamSettings {
  SceneView view;  // camera filled in per frame
  bool png = false;
  int jpeg_quality = 85;
  std::vector<SliceRequest> slices;  // A frame's encoding from the wire's fields: InvalidArgument naming
// `prefix` + "encoding" or "jpeg_quality" (0: 85).
struct FrameEncoding {
  bool png = false;
  int jpeg_quality = 85;
};
Result<FrameEncoding> ToFrameEncoding(v2::Encoding encoding, int32_t jpeg_quality,
                                      std::string_view prefix);

// RenderSettings.slices: with every frame
};
// InvalidArgument names the field ("settings.width: ..."); max_side caps
// width and height.
Result<StreamSettings> ToStreamSettings(const v2::RenderSettings& settings, const Volume& volume,
                                        int max_side);

// A frame's encoding from the wire's fields: InvalidArgument naming
// `prefix` + "encoding" or "jpeg_quality" (0: 85).
struct FrameEncoding {
  bool png = false;
  int jpeg_quality = 85;
};
Result<FrameEncoding> ToFrameEncoding(v2::Encoding encoding, int32_t jpeg_quality,
                                      std::string_view prefix);

// RenderSettings.slices (at most kMaxSlicesPerFrame, each view tag once),
// appended to `out`.
Status ToSliceRequests(const v2::RenderSettings& settings, const Volume& volume, int max_side,
                       std::vector<SliceRequest>* out);

// The absolute pose of `camera` on `volume`'s default camera.
Result<Camera> ToCamera(const v2::Camera& camera, const VolumeGeometry& geometry);
v2::Camera FromCamera(const Camera& camera);

}  // namespace vpm::service

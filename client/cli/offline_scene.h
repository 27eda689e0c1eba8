// What `vpm render` and `vpm slice` do offline before their output: read the
// volume, upload it, load or build the mesh (refined at the grab), set up
// the scene and apply the grab and the drag or pull. The flags are
// RenderArgs; each command adds its own output flags.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "client/cli/clip_flags.h"
#include "client/cli/mesh_flags.h"
#include "client/cli/volume_flags.h"
#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/mesh/proxy_mesh.h"
#include "server/raycast/volume_renderer.h"
#include "server/scene/deformable_scene.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/volume.h"

namespace vpm::cli {

struct RenderArgs {
  std::string source, mesh_json, out, out_volume, out_displacement;
  MeshFlags mesh;
  std::vector<double> camera;  // AZ EL DIST
  std::string mode = "dvr", preset = "auto", quality = "still";
  std::string render_tf;        // a ParaView .json[#NAME] or Slicer .vp; overrides preset
  std::vector<double> window;   // MIP: W L (the volume's units)
  double step_mm = 0.0;         // the sample step; 0: the quality's default
  // --quality interactive: auto (the device's choice) | fast | balanced | sharp
  std::string interactive_quality = "auto";
  std::vector<double> grab, drag, pull;
  std::vector<double> pins;  // 3 per --pin: X Y Z, mm
  std::string grab_landmark;
  std::string grab_rule = "organ";  // organ | ball
  double grab_radius = 0.0;
  std::vector<int> size{512, 512};
  bool overlay = false;
  int jpeg_quality = 90;
  ClipFlags clip;
  VolumeFlags volume_flags;
};

// The grab and drag flags (--grab, --grab-landmark, --grab-rule,
// --grab-radius, --pin, --drag, --pull), shared by the commands that deform.
void AddGrabFlags(CLI::App* app, RenderArgs* args);

// --window W L: MIP black at L - W/2, white at L + W/2; empty: none.
Result<std::optional<MipWindow>> WindowOf(const std::vector<double>& w);

Result<glm::dvec3> Vec3Of(const std::vector<double>& v, const char* flag);

// Members in the order they must be built; destroyed in reverse.
struct OfflineScene {
  std::optional<Volume> volume;  // set by PrepareOfflineScene
  std::unique_ptr<gpu::GpuContext> context;
  std::optional<GpuVolume> gpu_volume;
  ProxyMesh mesh;
  std::unique_ptr<VolumeRenderer> renderer;
  std::unique_ptr<DeformableScene> scene;
  std::optional<glm::dvec3> grab;  // physical mm
  SceneStepTimings step;           // of the drag or pull, zeros without one
  double load_ms = 0.0, upload_ms = 0.0, mesh_ms = 0.0, setup_ms = 0.0;
};

// Reads, meshes, grabs and drags as the flags say; prints the grab.
Result<std::unique_ptr<OfflineScene>> PrepareOfflineScene(const RenderArgs& args);
// The 3D view of the flags (camera, mode, preset, quality, size, overlay, clip).
Result<SceneView> MakeView(const RenderArgs& args, const Volume& volume);
// "stage ms" rows for load, upload, mesh and FEM setup.
void PrintSetupTimings(const OfflineScene& offline);

}  // namespace vpm::cli

#include "client/cli/mesh_command.h"

#include <cstdio>
#include <iostream>

#include "client/common/command_status.h"
#include "client/cli/gpu_backend.h"
#include "client/cli/mesh_flags.h"
#include "client/common/progress_bar.h"
#include "client/cli/remote_pipeline.h"
#include "client/cli/volume_flags.h"
#include "server/mesh/mesh_frame.h"
#include "server/mesh/mesh_json.h"
#include "server/mesh/write_vtu.h"
#include "server/io/read_volume.h"

namespace vpm::cli {
namespace {

struct MeshArgs {
  std::string source;
  MeshFlags mesh;
  std::string json_out, vtu_out, backend = "auto";
  VolumeFlags volume_flags;
};

// `evaluated_on`: where step 1 ran (MeshStats.evaluated_on; "server: ..." for a
// mesh the server built).
void PrintSummary(const ProxyMesh& mesh, const GpuBackend* gpu, const std::string& evaluated_on) {
  const MeshStats& s = mesh.stats;
  std::printf("lattice %dx%dx%d = %lld vertices, h = %.2f mm, R = %.2f mm\n", s.grid[0],
              s.grid[1], s.grid[2], static_cast<long long>(s.lattice_vertices), s.h_mm, s.R_mm);
  std::printf(
      "kept %lld lattice + %lld anchors + %lld refined + %lld boundary + %lld steiner = %zu "
      "vertices, %lld hard\n",
      static_cast<long long>(s.kept_lattice), static_cast<long long>(s.anchors),
      static_cast<long long>(s.refined), static_cast<long long>(s.boundary),
      static_cast<long long>(s.steiner), mesh.vertices.size(),
              static_cast<long long>(s.hard));
  std::printf("tets %zu, min dihedral %.2f deg, min radius ratio %.3f, removed flat %lld\n",
              mesh.tets.size(), mesh.quality.min_dihedral_deg, mesh.quality.min_radius_ratio,
              static_cast<long long>(mesh.quality.removed_zero_volume));
  std::printf("%-18s %9s\n", "stage", "ms");
  if (gpu != nullptr) std::printf("%-18s %9.2f\n", "upload (once)", gpu->upload_ms());
  std::printf("%-18s %9.2f  (%s)\n", "evaluate", s.evaluate_ms, evaluated_on.c_str());
  std::printf(
      "%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s "
      "%9.2f\n",
      "decimate", s.decimate_ms, "refine", s.refine_ms, "boundary", s.boundary_ms, "classify",
      s.classify_ms, "tetrahedralize", s.tetrahedralize_ms, "steiner", s.steiner_ms, "total",
      s.total_ms);
}

Result<ProxyMesh> BuildOnServer(const ServerFlags& server, const MeshArgs& args) {
  if (args.backend != "auto") {
    return absl::InvalidArgumentError("--backend is offline only: the server picks its own device");
  }
  ASSIGN_OR_RETURN(ServerConnection connection, ServerConnection::Connect(server));
  ASSIGN_OR_RETURN(RemoteMesh remote, BuildMeshOnServer(connection, args.source, args.mesh));
  std::printf("server %s: volume %s, mesh %s\n", server.address.c_str(),
              remote.volume.volume_id().c_str(), remote.info.mesh_id().c_str());
  PrintSummary(remote.mesh, nullptr,
               remote.mesh.stats.evaluated_on.empty()
                   ? std::string("server, which did not say where")
                   : StrCat("server: ", remote.mesh.stats.evaluated_on));
  return std::move(remote.mesh);
}

Result<ProxyMesh> BuildOffline(const MeshArgs& args) {
  // The bar: reading 0..0.5, upload 0.5..0.6, steps 1-2 0.6..0.9, the rest.
  ProgressBar bar(StrCat("meshing ", args.source), ProgressWanted(args.volume_flags.progress));
  const ProgressFn progress = bar.Reporter();
  ASSIGN_OR_RETURN(Volume volume, ReadVolumeForCli(args.source, args.volume_flags,
                                                   SubProgress(progress, 0.0, 0.5)));
  ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(args.mesh, volume));
  ASSIGN_OR_RETURN(auto gpu,
                   GpuBackend::Open(args.backend, volume, SubProgress(progress, 0.5, 0.6)));
  progress(0.6, "steps 1-2");
  ASSIGN_OR_RETURN(DecimatedLattice base,
                   DecimateLattice(volume, params, gpu ? gpu->mesh_gpu() : MeshGpu{}));
  progress(0.9, "steps 3-4, tets");
  ASSIGN_OR_RETURN(ProxyMesh mesh, FinishProxyMesh(volume, base, params));
  progress(1.0, "done");
  bar.Finish();
  // Step 1 says where it ran: on lavapipe the costs run as native rows on
  // the CPU, not as Vulkan kernels.
  PrintSummary(mesh, gpu.get(),
               gpu ? StrCat(mesh.stats.evaluated_on, "; Vulkan device ", gpu->context().device_name())
                   : mesh.stats.evaluated_on);
  return MeshToWorld(mesh, volume.geometry());  // the files are world LPS, as the server's
}

Status Run(const ServerFlags& server, const MeshArgs& args) {
  ASSIGN_OR_RETURN(ProxyMesh mesh,
                   server.address.empty() ? BuildOffline(args) : BuildOnServer(server, args));
  if (!args.json_out.empty()) {
    RETURN_IF_ERROR(WriteMeshJson(mesh, args.json_out));
    std::cout << "wrote " << args.json_out << "\n";
  }
  if (!args.vtu_out.empty()) {
    RETURN_IF_ERROR(WriteVtu(mesh, args.vtu_out));
    std::cout << "wrote " << args.vtu_out << "\n";
  }
  return absl::OkStatus();
}

}  // namespace

void AddMeshCommand(CLI::App& app, const ServerFlags* server, int* exit_code) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand("mesh", "Build the volume proxy mesh of a volume (offline, or on --server)");
  cmd->add_option("--volume", args->source,
                  "a file, a DICOM folder, phantom:NAME or raw:PATH?...")->required();
  AddMeshFlags(cmd, &args->mesh);
  AddVolumeFlags(cmd, &args->volume_flags);
  cmd->add_option("--json", args->json_out, "write vertices, tets and stats as JSON");
  cmd->add_option("--vtu", args->vtu_out, "write a VTK unstructured grid (ParaView, Slicer)");
  AddBackendFlag(cmd, &args->backend);
  cmd->callback([server, args, exit_code] { *exit_code = ExitWith(Run(*server, *args)); });
}

}  // namespace vpm::cli

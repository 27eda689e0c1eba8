#include "client/cli/mesh_command.h"

#include <cstdio>
#include <iostream>

#include "client/cli/command_status.h"
#include "client/cli/gpu_backend.h"
#include "client/cli/mesh_flags.h"
#include "server/mesh/mesh_json.h"
#include "server/mesh/write_vtu.h"
#include "server/volume/read_volume.h"

namespace vpm::cli {
namespace {

struct MeshArgs {
  std::string source;
  MeshFlags mesh;
  std::string json_out, vtu_out, backend = "auto";
};

void PrintSummary(const ProxyMesh& mesh, const GpuBackend* gpu) {
  const MeshStats& s = mesh.stats;
  std::printf("lattice %dx%dx%d = %lld vertices, h = %.2f mm, R = %.2f mm\n", s.grid[0],
              s.grid[1], s.grid[2], static_cast<long long>(s.lattice_vertices), s.h_mm, s.R_mm);
  std::printf("kept %lld lattice + %lld anchors + %lld refined = %zu vertices, %lld hard\n",
              static_cast<long long>(s.kept_lattice), static_cast<long long>(s.anchors),
              static_cast<long long>(s.refined), mesh.vertices.size(),
              static_cast<long long>(s.hard));
  std::printf("tets %zu, min dihedral %.2f deg, min radius ratio %.3f, removed flat %lld\n",
              mesh.tets.size(), mesh.quality.min_dihedral_deg, mesh.quality.min_radius_ratio,
              static_cast<long long>(mesh.quality.removed_zero_volume));
  std::printf("%-18s %9s\n", "stage", "ms");
  if (gpu != nullptr) std::printf("%-18s %9.2f\n", "upload (once)", gpu->upload_ms());
  std::printf("%-18s %9.2f  (%s)\n", "evaluate", s.evaluate_ms, gpu ? "GPU" : "CPU reference");
  std::printf("%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n%-18s %9.2f\n", "decimate",
              s.decimate_ms, "refine", s.refine_ms, "classify", s.classify_ms, "tetrahedralize",
              s.tetrahedralize_ms, "total", s.total_ms);
}

Status Run(const MeshArgs& args) {
  ASSIGN_OR_RETURN(Volume volume, ReadVolume(args.source, VolumeLimits{}));
  ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(args.mesh, volume));
  ASSIGN_OR_RETURN(auto gpu, GpuBackend::Open(args.backend, volume));
  ASSIGN_OR_RETURN(ProxyMesh mesh,
                   BuildProxyMesh(volume, params, gpu ? gpu->mesh_gpu() : MeshGpu{}));
  PrintSummary(mesh, gpu.get());
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

void AddMeshCommand(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand("mesh", "Build the volume proxy mesh of a volume (offline)");
  cmd->add_option("--volume", args->source,
                  "a file, a DICOM folder, phantom:NAME or raw:PATH?...")->required();
  AddMeshFlags(cmd, &args->mesh);
  cmd->add_option("--json", args->json_out, "write vertices, tets and stats as JSON");
  cmd->add_option("--vtu", args->vtu_out, "write a VTK unstructured grid (ParaView, Slicer)");
  AddBackendFlag(cmd, &args->backend);
  cmd->callback([args, exit_code] { *exit_code = ExitWith(Run(*args)); });
}

}  // namespace vpm::cli

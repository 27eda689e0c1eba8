#include "client/cli/compare_meshes_command.h"

#include <algorithm>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "client/common/command_status.h"
#include "client/cli/volume_flags.h"
#include "client/cli/gpu_backend.h"
#include "client/cli/mesh_flags.h"
#include "server/measures/compare_meshes.h"
#include "server/common/write_file.h"
#include "server/measures/deformation_measures.h"
#include "server/io/read_volume.h"

namespace vpm::cli {
namespace {

struct CompareArgs {
  std::string source;
  MeshFlags mesh;
  std::string backend = "auto", json_out;
  bool deformation = true;
  std::string drag_landmark = StandardDrag{}.landmark;
  std::vector<double> drag{StandardDrag{}.offset_mm.x, StandardDrag{}.offset_mm.y,
                           StandardDrag{}.offset_mm.z};
  double grab_radius_factor = StandardDrag{}.grab_radius_factor;
  std::vector<double> grab;  // X Y Z mm: the grab point instead of the landmark
  VolumeFlags volume_flags;
};

// `drag` in physical voxel space, printed in world LPS as the user gave it.
void PrintDeformation(const std::vector<DeformationMeasure>& rows, const StandardDrag& drag,
                      const VolumeGeometry& geometry) {
  const glm::dvec3 point = drag.point_mm ? geometry.PhysicalToWorld(*drag.point_mm) : glm::dvec3();
  const glm::dvec3 offset = geometry.PhysicalVectorToWorld(drag.offset_mm);
  const std::string at =
      drag.point_mm ? StrCat("(", point.x, ", ", point.y, ", ", point.z, ") mm (LPS)")
                    : StrCat("'", drag.landmark, "'");
  std::printf(
      "\ndeformation: grab %s (radius %.2f h), drag (%.1f, %.1f, %.1f) mm; error vs the "
      "dense-lattice reference over body voxels (every 4th per axis)\n",
      at.c_str(), drag.grab_radius_factor, offset.x, offset.y, offset.z);
  std::printf("%-10s %6s %8s %8s %10s %10s %12s %11s %12s %9s  %s\n", "mesh", "verts",
              "handles", "min dih", "RMS mm", "max mm", "bone max %", "inverted", "inv @1.5h",
              "FEM ms", "worst bone voxel (mm, LPS)");
  for (const auto& r : rows) {
    const glm::dvec3 worst = geometry.PhysicalToWorld(r.bone_worst_mm);
    std::printf(
        "%-10s %6lld %8lld %8.2f %10.3f %10.3f %12.2f %11lld %12lld %9.1f  (%.0f, %.0f, %.0f)%s\n",
        r.name.c_str(), static_cast<long long>(r.vertices), static_cast<long long>(r.handles),
        r.min_dihedral_deg, r.rms_error_mm, r.max_error_mm, 100.0 * r.bone_max_fraction,
        static_cast<long long>(r.inverted_at_drag), static_cast<long long>(r.inverted_at_1_5h),
        r.solve_ms, worst.x, worst.y, worst.z,
        r.converged ? "" : " (not converged)");
  }
  for (const auto& r : rows) {
    if (r.forced_at_drag || r.forced_at_1_5h) {
      std::printf(
          "%s: the solver found no feasible load step for the drag (%s) and forced it "
          "(docs/FEM.md, \"Forced inversions\": handles and a fixed vertex in one tet, or "
          "tets crushed beside the handles)\n",
          r.name.c_str(),
          r.forced_at_drag ? (r.forced_at_1_5h ? "the standard one and 1.5 h" : "the standard one")
                           : "1.5 h");
    }
  }
}

void PrintTable(const std::vector<MeshComparisonRow>& rows) {
  std::printf("%-14s %6s %8s %6s %12s %14s %12s %10s %10s\n", "mesh", "verts", "steiner",
              "tets", "RMSE all", "RMSE TF>0", "empty R mm", "min dih", "build ms");
  for (const auto& r : rows) {
    std::printf("%-14s %6lld %8lld %6lld %12.2f %14.2f %12.2f %10.2f %10.1f%s\n",
                (r.name + (r.is_default ? "*" : "")).c_str(), static_cast<long long>(r.vertices),
                static_cast<long long>(r.steiner_vertices), static_cast<long long>(r.tets), r.reconstruction.rmse_all,
                r.reconstruction.rmse_tf_positive, r.largest_empty_sphere.radius_mm,
                r.quality.min_dihedral_deg, r.build_ms, "");
  }
  std::printf(
      "* default (point footprint, spread). RMSE in volume units (HU); empty R: largest "
      "empty sphere centred in the body (TF > 0); min dih: smallest dihedral angle, deg\n");
}

Status WriteJson(const std::vector<MeshComparisonRow>& rows, const std::string& path) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& r : rows) {
    out.push_back({{"mesh", r.name},
                   {"default", r.is_default},
                   {"vertices", r.vertices},
                   {"steiner_vertices", r.steiner_vertices},
                   {"tets", r.tets},
                   {"rmse_all", r.reconstruction.rmse_all},
                   {"rmse_tf_positive", r.reconstruction.rmse_tf_positive},
                   {"largest_empty_sphere_mm", r.largest_empty_sphere.radius_mm},
                   {"min_dihedral_deg", r.quality.min_dihedral_deg},
                   {"build_ms", r.build_ms}});
  }
  return WriteFile(path, out.dump(2) + "\n");
}

Status Run(const CompareArgs& args) {
  ASSIGN_OR_RETURN(Volume volume, ReadVolumeForCli(args.source, args.volume_flags));
  ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(args.mesh, volume));
  ASSIGN_OR_RETURN(auto gpu, GpuBackend::Open(args.backend, volume));
  ASSIGN_OR_RETURN(auto rows, CompareMeshes(volume, params, gpu ? gpu->mesh_gpu() : MeshGpu{}));
  PrintTable(rows);
  if (!args.json_out.empty()) RETURN_IF_ERROR(WriteJson(rows, args.json_out));
  if (!args.deformation) return absl::OkStatus();
  const bool has_landmark =
      args.grab.size() == 3 ||
      std::any_of(volume.landmarks().begin(), volume.landmarks().end(),
                  [&](const Landmark& l) { return l.name == args.drag_landmark; });
  if (!has_landmark) {
    std::printf("\ndeformation measures skipped: %s has no landmark '%s' (--drag-landmark; "
                "--grab X Y Z grabs anywhere)\n",
                volume.source().c_str(), args.drag_landmark.c_str());
    return absl::OkStatus();
  }
  // --grab and --drag are world LPS; the measures work in physical voxel space.
  const VolumeGeometry& geometry = volume.geometry();
  StandardDrag drag{.landmark = args.drag_landmark,
                    .offset_mm = geometry.WorldVectorToPhysical(
                        glm::dvec3(args.drag[0], args.drag[1], args.drag[2])),
                    .grab_radius_factor = args.grab_radius_factor};
  if (args.grab.size() == 3) {
    drag.point_mm = geometry.WorldToPhysical(glm::dvec3(args.grab[0], args.grab[1], args.grab[2]));
  }
  ASSIGN_OR_RETURN(auto deformation, CompareDeformation(volume, params, drag));
  PrintDeformation(deformation, drag, geometry);
  return absl::OkStatus();
}

}  // namespace

void AddCompareMeshesCommand(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare-meshes", "Compare a regular lattice with the optimized meshes (same budget)");
  cmd->add_option("--volume", args->source, "a file, a DICOM folder or phantom:NAME")->required();
  AddMeshFlags(cmd, &args->mesh);
  AddVolumeFlags(cmd, &args->volume_flags);
  cmd->add_option("--json", args->json_out, "also write the table as JSON");
  cmd->add_flag("!--no-deformation", args->deformation,
                "skip the deformation measures (FEM on each mesh and on the dense reference)");
  cmd->add_option("--drag-landmark", args->drag_landmark, "the standard drag's grab point")
      ->capture_default_str();
  cmd->add_option("--grab", args->grab,
                  "the drag's grab point X Y Z (mm, world LPS) instead of a landmark")
      ->expected(3);
  cmd->add_option("--drag", args->drag, "the standard drag, DX DY DZ mm (world LPS)")
      ->expected(3)
      ->capture_default_str();
  cmd->add_option("--grab-radius", args->grab_radius_factor,
                  "the standard drag's grab radius, in lattice steps h")
      ->check(CLI::Range(0.01, 10.0))
      ->capture_default_str();
  AddBackendFlag(cmd, &args->backend);
  cmd->callback([args, exit_code] { *exit_code = ExitWith(Run(*args)); });
}

}  // namespace vpm::cli

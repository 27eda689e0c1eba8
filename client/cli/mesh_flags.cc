#include "client/cli/mesh_flags.h"

namespace vpm::cli {

std::string TransferFunctionHelp() {
  std::string text = "transfer cost: a preset or VALUE:COST,VALUE:COST,... Presets:";
  for (const auto& [name, description] : TransferFunction::PresetNames()) {
    text += "\n    " + name + ": " + description;
  }
  return text;
}

void AddMeshFlags(CLI::App* app, MeshFlags* f) {
  app->add_option("--grid", f->grid, "lattice G: GX GY GZ vertices")->expected(3)
      ->capture_default_str();
  app->add_option("--target", f->target, "vertices to keep, the 8 corner anchors included")
      ->capture_default_str();
  app->add_option("--footprint", f->footprint, "point (the voxel nearest the vertex) or "
                  "cell (mean TF, max gradient over the cell)")
      ->check(CLI::IsMember({"point", "cell"}))->capture_default_str();
  app->add_option("--density-mode", f->density_mode,
                  "spread: S = 1 - Cd (crowded vertices go first); paper: S = Cd")
      ->check(CLI::IsMember({"spread", "paper"}))->capture_default_str();
  app->add_option("--wg", f->wg, "weight of the gradient term")->capture_default_str();
  app->add_option("--wd", f->wd, "weight of the spreading term")->capture_default_str();
  app->add_option("--radius-factor", f->radius_factor, "density radius R = factor * h")
      ->capture_default_str();
  app->add_option("--tf", f->tf, TransferFunctionHelp())->capture_default_str();
  app->add_option(
         "--bone", f->bone,
         "bone threshold (HU; CT in HU only, none on an MRI): vertices at or above are hard")
      ->capture_default_str();
  app->add_option("--influence-threshold", f->influence_threshold,
                  "HU at or above which a vertex near bone becomes hard")->capture_default_str();
  app->add_option("--influence-factor", f->influence_factor,
                  "influence radius = factor * R")->capture_default_str();
  app->add_option("--refine-at", f->refine_at,
                  "manipulation point X Y Z (mm, world LPS, as `vpm volume info`)")
      ->expected(3);
  app->add_option("--refine-at-landmark", f->refine_at_landmark,
                  "refine at a named landmark of the volume (see `vpm volume info`)");
  app->add_option("--roi-factor", f->roi_factor, "refinement radius = factor * h")
      ->capture_default_str();
  app->add_option("--refine-count", f->refine_count, "most refinement vertices")
      ->capture_default_str();
  app->add_option("--steiner-min-dihedral", f->steiner_min_dihedral,
                  "add Steiner points until every tet's smallest dihedral angle reaches this "
                  "(degrees; 0: none, the tets of Delaunay and flips alone)")
      ->check(CLI::Range(0.0, 15.0))
      ->capture_default_str();
}

Result<MeshParams> ToMeshParams(const MeshFlags& f, const Volume& volume) {
  MeshParams p;
  if (f.grid.size() != 3) return absl::InvalidArgumentError("--grid takes 3 integers");
  p.grid = {f.grid[0], f.grid[1], f.grid[2]};
  p.target = f.target;
  ASSIGN_OR_RETURN(p.footprint, ParseFootprint(f.footprint));
  ASSIGN_OR_RETURN(p.density_mode, ParseDensityMode(f.density_mode));
  p.wg = f.wg;
  p.wd = f.wd;
  p.radius_factor = f.radius_factor;
  p.tf = f.tf;
  p.classify.bone_threshold = f.bone;
  p.classify.influence_threshold = f.influence_threshold;
  p.classify.influence_factor = f.influence_factor;
  if (!f.refine_at.empty()) {
    if (f.refine_at.size() != 3) return absl::InvalidArgumentError("--refine-at takes X Y Z");
    // World LPS on the command line; the mesh is built in physical voxel space.
    p.refine_at_mm = volume.geometry().WorldToPhysical(
        glm::dvec3(f.refine_at[0], f.refine_at[1], f.refine_at[2]));
  }
  if (!f.refine_at_landmark.empty()) {
    if (p.refine_at_mm) {
      return absl::InvalidArgumentError("give --refine-at or --refine-at-landmark, not both");
    }
    std::string names;
    for (const Landmark& l : volume.landmarks()) {
      if (l.name == f.refine_at_landmark) p.refine_at_mm = l.position_mm;
      names += (names.empty() ? "" : ", ") + l.name;
    }
    if (!p.refine_at_mm) {
      return absl::NotFoundError(StrCat("landmark '", f.refine_at_landmark, "' is not in ",
                                        volume.source(), " (it has: ",
                                        names.empty() ? "none" : names, ")"));
    }
  }
  p.roi_radius_factor = f.roi_factor;
  p.refine_count = f.refine_count;
  p.steiner_min_dihedral_deg = f.steiner_min_dihedral;
  return p;
}

}  // namespace vpm::cli

// The volume proxy mesh (VPM): the vertices kept by steps 2-4 of
// docs/ALGORITHM.md, their classification, and their tetrahedralization.
// Positions are in physical voxel space (mm): index * spacing.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

enum class VertexKind {
  kLattice,  // a step-2 survivor of the regular lattice
  kAnchor,   // one of the 8 corners of the image box
  kRefined,  // a step-4 vertex around the manipulation point
  kBoundary,  // on a face of the image box, added so that no tet there is a
              // sliver (boundary_vertices.h)
  kSteiner,   // added where no flip could mend a tet under 5 degrees
              // (sliver_steiner_points.h) or on a long edge from a hard
              // vertex near the refinement point (hard_reach_steiner_points.h)
};
// "lattice", "anchor", "refined", "boundary", "steiner"
const char* VertexKindName(VertexKind kind);

struct MeshVertex {
  glm::dvec3 position_mm{0.0};  // physical voxel space
  int64_t lattice_id = -1;      // a + Gx*(b + Gy*c) for lattice vertices, -1 otherwise
  VertexKind kind = VertexKind::kLattice;
  std::array<int64_t, 3> voxel{0, 0, 0};  // voxel(v): nearest voxel (round half up, clamped)
  bool hard = false;            // non-deformable (step 3): stiff
  // Hard and part of the skeleton (classify_hardness.h): fixed in space. A
  // hard vertex off the skeleton (a stone, a calcification) is stiff but
  // moves with the tissue around it. Implies hard.
  bool skeleton = false;
  // Lattice: Ctotal when decimation stopped; refined: its Ci*Cg score;
  // anchor: 0.
  double cost = 0.0;
};

// Tet quality over all tets (section 5).
struct TetQuality {
  double min_dihedral_deg = 0.0;   // smallest dihedral angle of any tet, degrees
  double mean_min_dihedral_deg = 0.0;
  double min_radius_ratio = 0.0;   // 3 * inradius / circumradius, 1 for regular, -> 0 degenerate
  double mean_radius_ratio = 0.0;
  int64_t removed_zero_volume = 0; // tets dropped as (near) zero volume
};

// Counts, scales and stage timings of one build (the `stats` of --json).
// Where step 1 (the lattice costs) ran: MeshStats.evaluated_on.
inline constexpr char kStep1OnGpu[] = "GPU kernels";
inline constexpr char kStep1OnCpuRows[] = "CPU rows, the Vulkan device being a CPU";
inline constexpr char kStep1OnCpuReference[] = "CPU reference";

struct MeshStats {
  std::array<int32_t, 3> grid{0, 0, 0};  // lattice G
  int64_t lattice_vertices = 0;          // Gx*Gy*Gz
  int64_t kept_lattice = 0;              // step-2 survivors (anchors excluded)
  int64_t anchors = 0;
  int64_t refined = 0;
  int64_t boundary = 0;  // on the box faces (boundary_vertices.h)
  int64_t steiner = 0;   // against slivers and long hard edges (kSteiner)
  int64_t hard = 0;
  int64_t tets = 0;
  double h_mm = 0.0;  // largest lattice step
  double R_mm = 0.0;  // density radius
  double evaluate_ms = 0.0;
  std::string evaluated_on;  // one of kStep1On*; empty when not known (a mesh read back)
  double decimate_ms = 0.0;
  double classify_ms = 0.0;
  double refine_ms = 0.0;
  double boundary_ms = 0.0;
  double steiner_ms = 0.0;  // Steiner rounds, their tetrahedralizations included
  double tetrahedralize_ms = 0.0;
  double total_ms = 0.0;
};

struct ProxyMesh {
  std::vector<MeshVertex> vertices;
  // Vertex index quadruples, each with positive signed volume
  // (det[p1-p0, p2-p0, p3-p0] > 0).
  std::vector<std::array<int32_t, 4>> tets;
  TetQuality quality;
  MeshStats stats;
};

}  // namespace vpm

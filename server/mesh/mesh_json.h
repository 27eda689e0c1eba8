// The proxy mesh as JSON (the `vpm mesh --json` output, read back by
// `vpm render --mesh-json`).
//
// {"vertices": [{"lattice_id": int, "kind": "lattice|anchor|refined|boundary|steiner",
//                "position_mm": [x, y, z], "hard": bool, "skeleton": bool (hard and fixed; absent: = hard), "cost": double}, ...],
//  "tets": [[a, b, c, d], ...],
//  "stats": {"grid": [gx, gy, gz], "lattice_vertices", "kept_lattice",
//            "anchors", "refined", "boundary", "steiner" (both optional on
//            reading), "hard", "tets", "h_mm", "R_mm",
//            "evaluate_ms", "decimate_ms", "classify_ms", "refine_ms",
//            "tetrahedralize_ms", "total_ms",
//            "quality": {"min_dihedral_deg", "mean_min_dihedral_deg",
//                        "min_radius_ratio", "mean_radius_ratio",
//                        "removed_zero_volume"}}}
// Doubles are written with 17 significant digits, so a round trip is exact.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

// The whole mesh: #V vertices, #T tets, stats and quality.
nlohmann::json MeshToJson(const ProxyMesh& mesh);

// Parses and validates MeshToJson's layout: every field present with the
// right type, numbers finite, kinds known, tet indices in [0, #V) and
// distinct, each tet with positive signed volume (the ProxyMesh invariant).
// Errors name what is wrong (`vertices[3].kind`).
Result<ProxyMesh> MeshFromJson(const nlohmann::json& json);

// MeshToJson written to `path` (compact, one line); fails on non-finite numbers
// (JSON has none) or I/O errors, naming the file.
Status WriteMeshJson(const ProxyMesh& mesh, const std::string& path);

// Reads and validates a file written by WriteMeshJson; errors name the file.
Result<ProxyMesh> ReadMeshJson(const std::string& path);

}  // namespace vpm

// The proxy mesh as JSON: round trip and validation.
#include "server/mesh/mesh_json.h"

#include <fstream>

#include <gtest/gtest.h>

#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using nlohmann::json;

ProxyMesh SampleMesh() {
  const glm::dvec3 extent(12.5, 7.25, 3.0 / 7.0);
  ProxyMesh mesh = testing::RandomMesh(30, extent, 21);
  mesh.vertices[3].kind = VertexKind::kRefined;
  mesh.vertices[3].lattice_id = -1;
  mesh.vertices[3].cost = 1.0 / 3.0;
  mesh.vertices[5].hard = true;
  mesh.vertices[6].cost = -2.5e-17;
  EXPECT_TRUE(Tetrahedralize(mesh, extent).ok());
  mesh.stats.grid = {20, 21, 22};
  mesh.stats.lattice_vertices = 20 * 21 * 22;
  mesh.stats.kept_lattice = 29;
  mesh.stats.anchors = 8;
  mesh.stats.refined = 1;
  mesh.stats.hard = 1;
  mesh.stats.h_mm = 0.1 + 0.2;
  mesh.stats.R_mm = 2.0 * (0.1 + 0.2);
  mesh.stats.evaluate_ms = 1.25;
  mesh.stats.decimate_ms = 3.5;
  mesh.stats.classify_ms = 0.125;
  mesh.stats.refine_ms = 7.0;
  mesh.stats.total_ms = 100.0 / 3.0;
  return mesh;
}

// In a folder of the current test's own (tests of this file run side by side).
std::string TempPath(const std::string& name) { return (testing::MakeTempDir() / name).string(); }

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

void ExpectSameMesh(const ProxyMesh& a, const ProxyMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) {
    EXPECT_EQ(a.vertices[v].position_mm, b.vertices[v].position_mm) << v;
    EXPECT_EQ(a.vertices[v].lattice_id, b.vertices[v].lattice_id) << v;
    EXPECT_EQ(a.vertices[v].kind, b.vertices[v].kind) << v;
    EXPECT_EQ(a.vertices[v].hard, b.vertices[v].hard) << v;
    EXPECT_EQ(a.vertices[v].cost, b.vertices[v].cost) << v;
  }
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.stats.grid, b.stats.grid);
  EXPECT_EQ(a.stats.lattice_vertices, b.stats.lattice_vertices);
  EXPECT_EQ(a.stats.kept_lattice, b.stats.kept_lattice);
  EXPECT_EQ(a.stats.anchors, b.stats.anchors);
  EXPECT_EQ(a.stats.refined, b.stats.refined);
  EXPECT_EQ(a.stats.hard, b.stats.hard);
  EXPECT_EQ(a.stats.tets, b.stats.tets);
  EXPECT_EQ(a.stats.h_mm, b.stats.h_mm);
  EXPECT_EQ(a.stats.R_mm, b.stats.R_mm);
  EXPECT_EQ(a.stats.evaluate_ms, b.stats.evaluate_ms);
  EXPECT_EQ(a.stats.decimate_ms, b.stats.decimate_ms);
  EXPECT_EQ(a.stats.classify_ms, b.stats.classify_ms);
  EXPECT_EQ(a.stats.refine_ms, b.stats.refine_ms);
  EXPECT_EQ(a.stats.tetrahedralize_ms, b.stats.tetrahedralize_ms);
  EXPECT_EQ(a.stats.total_ms, b.stats.total_ms);
  EXPECT_EQ(a.quality.min_dihedral_deg, b.quality.min_dihedral_deg);
  EXPECT_EQ(a.quality.mean_min_dihedral_deg, b.quality.mean_min_dihedral_deg);
  EXPECT_EQ(a.quality.min_radius_ratio, b.quality.min_radius_ratio);
  EXPECT_EQ(a.quality.mean_radius_ratio, b.quality.mean_radius_ratio);
  EXPECT_EQ(a.quality.removed_zero_volume, b.quality.removed_zero_volume);
}

TEST(MeshJson, RoundTripIsExact) {
  const ProxyMesh mesh = SampleMesh();
  const std::string path = TempPath("mesh_round_trip.json");
  ASSERT_TRUE(WriteMeshJson(mesh, path).ok());
  auto back = ReadMeshJson(path);
  ASSERT_TRUE(back.ok()) << back.status();
  ExpectSameMesh(mesh, *back);
}

TEST(MeshJson, HasTheDocumentedLayout) {
  const ProxyMesh mesh = SampleMesh();
  const json j = MeshToJson(mesh);
  EXPECT_EQ(j["vertices"].size(), mesh.vertices.size());
  EXPECT_EQ(j["vertices"][3]["kind"], "refined");
  EXPECT_EQ(j["vertices"][0]["kind"], "lattice");
  EXPECT_EQ(j["vertices"][30]["kind"], "anchor");
  EXPECT_EQ(j["vertices"][5]["hard"], true);
  EXPECT_EQ(j["tets"].size(), mesh.tets.size());
  EXPECT_EQ(j["stats"]["grid"], json({20, 21, 22}));
  EXPECT_EQ(j["stats"]["tets"], static_cast<int64_t>(mesh.tets.size()));
  EXPECT_TRUE(j["stats"]["quality"].contains("min_radius_ratio"));
  EXPECT_TRUE(j["stats"].contains("tetrahedralize_ms"));
}

// Edits one field of a valid file and expects ReadMeshJson to name it.
void ExpectRejected(const std::function<void(json&)>& edit, const std::string& expected) {
  json j = MeshToJson(SampleMesh());
  edit(j);
  const std::string path = TempPath("mesh_bad.json");
  WriteText(path, j.dump());
  auto mesh = ReadMeshJson(path);
  ASSERT_FALSE(mesh.ok()) << expected;
  EXPECT_EQ(mesh.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string message(mesh.status().message());
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find(expected), std::string::npos) << message;
}

TEST(MeshJson, RejectsBadIndicesAndKinds) {
  ExpectRejected([](json& j) { j["tets"][2][1] = 38; }, "tets[2][1]");
  ExpectRejected([](json& j) { j["tets"][0][0] = -1; }, "tets[0][0]");
  ExpectRejected([](json& j) { j["tets"][0][3] = 1.5; }, "tets[0][3]");
  ExpectRejected([](json& j) { j["tets"][1] = json({1, 2, 3}); }, "tets[1]");
  ExpectRejected([](json& j) { j["tets"][1][1] = j["tets"][1][0]; }, "repeats");
  ExpectRejected([](json& j) { std::swap(j["tets"][1][2], j["tets"][1][3]); }, "signed volume");
  ExpectRejected([](json& j) { j["vertices"][4]["kind"] = "corner"; }, "vertices[4].kind");
  ExpectRejected([](json& j) { j["vertices"][4]["kind"] = 1; }, "vertices[4].kind");
  ExpectRejected([](json& j) { j["vertices"][4]["lattice_id"] = -1; }, "vertices[4].lattice_id");
}

TEST(MeshJson, RejectsMissingAndMistypedFields) {
  ExpectRejected([](json& j) { j["vertices"][1].erase("cost"); }, "vertices[1].cost is missing");
  ExpectRejected([](json& j) { j["vertices"][1]["cost"] = "cheap"; }, "vertices[1].cost");
  ExpectRejected([](json& j) { j["vertices"][1]["hard"] = 1; }, "vertices[1].hard");
  ExpectRejected(
      [](json& j) {
        j["vertices"][1]["position_mm"] = json({1, 2});
      },
      "vertices[1].position_mm");
  ExpectRejected([](json& j) { j["vertices"][1]["position_mm"][0] = nullptr; },
                 "vertices[1].position_mm");
  ExpectRejected([](json& j) { j.erase("stats"); }, "stats is missing");
  ExpectRejected([](json& j) { j["stats"]["grid"] = json({1, 2}); }, "stats.grid");
  ExpectRejected([](json& j) { j["stats"]["tets"] = -3; }, "stats.tets");
  ExpectRejected([](json& j) { j["stats"]["quality"].erase("min_dihedral_deg"); },
                 "stats.quality.min_dihedral_deg");
  ExpectRejected([](json& j) { j["vertices"] = json::object(); }, "vertices must be an array");
}

TEST(MeshJson, RejectsFilesThatAreNotJson) {
  const std::string path = TempPath("mesh_not_json.json");
  WriteText(path, "{\"vertices\": [");
  auto mesh = ReadMeshJson(path);
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.status().message().find(path), std::string::npos);
  WriteText(path, "{\"vertices\": [], \"tets\": [], \"stats\": {}, \"x\": 1e999}");
  EXPECT_FALSE(ReadMeshJson(path).ok());
  EXPECT_EQ(ReadMeshJson(TempPath("no_such_mesh.json")).status().code(),
            absl::StatusCode::kNotFound);
}

TEST(MeshJson, WriteRejectsNonFiniteNumbers) {
  ProxyMesh mesh = SampleMesh();
  mesh.vertices[2].cost = std::nan("");
  const Status status = WriteMeshJson(mesh, TempPath("mesh_nan.json"));
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("vertex 2"), std::string::npos) << status;
}

}  // namespace
}  // namespace vpm

// The proxy mesh as a VTK XML unstructured grid.
#include "server/mesh/write_vtu.h"

#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The whitespace-separated tokens of the DataArray (or Array) whose opening tag
// contains `marker` (e.g. Name="offsets").
std::vector<std::string> ArrayTokens(const std::string& xml, const std::string& marker) {
  const size_t tag = xml.find(marker);
  if (tag == std::string::npos) return {};
  const size_t begin = xml.find('>', tag) + 1;
  const size_t end = xml.find("</", begin);  // </DataArray> or </Array>
  std::istringstream in(xml.substr(begin, end - begin));
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  return tokens;
}

// Opening and closing tags balance (a small well-formedness check).
bool TagsBalance(const std::string& xml) {
  std::vector<std::string> open;
  const std::regex tag(R"(<(/?)([A-Za-z]+)[^>]*?(/?)>)");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), tag); it != std::sregex_iterator();
       ++it) {
    const auto& m = *it;
    if (m[3].length() > 0) continue;  // <x/>
    if (m[1].length() == 0) {
      open.push_back(m[2]);
    } else if (open.empty() || open.back() != m[2]) {
      return false;
    } else {
      open.pop_back();
    }
  }
  return open.empty();
}

TEST(WriteVtu, WritesTheRightCounts) {
  const glm::dvec3 extent(20.0, 10.0, 5.0);
  ProxyMesh mesh = testing::LatticeMesh(3, extent);
  mesh.vertices[0].hard = true;
  mesh.vertices[1].kind = VertexKind::kRefined;
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  const std::string path = (testing::MakeTempDir() / "mesh.vtu").string();
  ASSERT_TRUE(WriteVtu(mesh, path).ok());
  const std::string xml = ReadText(path);
  const size_t V = mesh.vertices.size(), T = mesh.tets.size();

  EXPECT_EQ(xml.rfind("<?xml", 0), 0u);
  EXPECT_TRUE(TagsBalance(xml.substr(xml.find("?>") + 2)));
  EXPECT_NE(xml.find("NumberOfPoints=\"" + std::to_string(V) + "\""), std::string::npos);
  EXPECT_NE(xml.find("NumberOfCells=\"" + std::to_string(T) + "\""), std::string::npos);
  EXPECT_EQ(ArrayTokens(xml, "NumberOfComponents=\"3\"").size(), 3 * V);
  EXPECT_EQ(ArrayTokens(xml, "Name=\"connectivity\"").size(), 4 * T);
  const auto offsets = ArrayTokens(xml, "Name=\"offsets\"");
  ASSERT_EQ(offsets.size(), T);
  EXPECT_EQ(offsets.back(), std::to_string(4 * T));
  const auto types = ArrayTokens(xml, "Name=\"types\"");
  ASSERT_EQ(types.size(), T);
  for (const std::string& t : types) EXPECT_EQ(t, "10");
  const auto hard = ArrayTokens(xml, "Name=\"hard\"");
  ASSERT_EQ(hard.size(), V);
  EXPECT_EQ(hard[0], "1");
  EXPECT_EQ(hard[1], "0");
  const auto kind = ArrayTokens(xml, "Name=\"kind\"");
  ASSERT_EQ(kind.size(), V);
  EXPECT_EQ(kind[0], "0");
  EXPECT_EQ(kind[1], "2");
  EXPECT_EQ(kind[V - 1], "1");
  EXPECT_EQ(ArrayTokens(xml, "Name=\"cost\"").size(), V);
  // The frame, as 3D Slicer reads it: a string array SPACE = "LPS".
  const auto space = ArrayTokens(xml, "Name=\"SPACE\"");
  ASSERT_EQ(space.size(), 4u);
  std::string name;
  for (int c = 0; c < 3; ++c) name += static_cast<char>(std::stoi(space[c]));
  EXPECT_EQ(name, "LPS");
  EXPECT_EQ(space[3], "0");
  // Connectivity is the tets, in order.
  const auto connectivity = ArrayTokens(xml, "Name=\"connectivity\"");
  EXPECT_EQ(connectivity[4], std::to_string(mesh.tets[1][0]));
}

TEST(WriteVtu, FailsOnAnUnwritablePath) {
  ProxyMesh mesh;
  const Status status = WriteVtu(mesh, "/nonexistent-dir/mesh.vtu");
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("/nonexistent-dir/mesh.vtu"), std::string::npos);
}

}  // namespace
}  // namespace vpm

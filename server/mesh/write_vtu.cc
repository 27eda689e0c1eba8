#include "server/mesh/write_vtu.h"

#include <limits>
#include <sstream>

#include "server/common/write_file.h"

namespace vpm {
namespace {

constexpr int kVtkTetra = 10;

int KindCode(VertexKind kind) {
  switch (kind) {
    case VertexKind::kLattice:
      return 0;
    case VertexKind::kAnchor:
      return 1;
    case VertexKind::kRefined:
      return 2;
    case VertexKind::kBoundary:
      return 3;
    case VertexKind::kSteiner:
      return 4;
  }
  return -1;
}

// One <DataArray> of the vertices, `value` giving each one's text.
template <typename Value>
void WritePointArray(std::ostream& out, const ProxyMesh& mesh, const char* type, const char* name,
                     Value value) {
  out << "        <DataArray type=\"" << type << "\" Name=\"" << name << "\" format=\"ascii\">\n";
  for (const MeshVertex& v : mesh.vertices) out << ' ' << value(v);
  out << "\n        </DataArray>\n";
}

}  // namespace

Status WriteVtu(const ProxyMesh& mesh, const std::string& path) {
  std::ostringstream out;
  out.precision(std::numeric_limits<double>::max_digits10);
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <UnstructuredGrid>\n"
      // A VTK XML ASCII string: its characters' codes, then 0.
      << "    <FieldData>\n"
      << "      <Array type=\"String\" Name=\"SPACE\" NumberOfTuples=\"1\" format=\"ascii\">\n"
      << "        76 80 83 0\n"
      << "      </Array>\n"
      << "    </FieldData>\n"
      << "    <Piece NumberOfPoints=\"" << mesh.vertices.size() << "\" NumberOfCells=\""
      << mesh.tets.size() << "\">\n"
      << "      <PointData Scalars=\"cost\">\n";
  WritePointArray(out, mesh, "UInt8", "hard", [](const MeshVertex& v) { return v.hard ? 1 : 0; });
  WritePointArray(out, mesh, "UInt8", "skeleton",
                  [](const MeshVertex& v) { return v.skeleton ? 1 : 0; });
  WritePointArray(out, mesh, "Float64", "cost", [](const MeshVertex& v) { return v.cost; });
  WritePointArray(out, mesh, "Int32", "kind", [](const MeshVertex& v) { return KindCode(v.kind); });
  WritePointArray(out, mesh, "Int64", "lattice_id",
                  [](const MeshVertex& v) { return v.lattice_id; });
  out << "      </PointData>\n"
      << "      <Points>\n"
      << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const MeshVertex& v : mesh.vertices) {
    out << "          " << v.position_mm.x << ' ' << v.position_mm.y << ' ' << v.position_mm.z
        << '\n';
  }
  out << "        </DataArray>\n"
      << "      </Points>\n"
      << "      <Cells>\n"
      << "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (const auto& t : mesh.tets) {
    out << "          " << t[0] << ' ' << t[1] << ' ' << t[2] << ' ' << t[3] << '\n';
  }
  out << "        </DataArray>\n"
      << "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (size_t t = 0; t < mesh.tets.size(); ++t) out << ' ' << 4 * (t + 1);
  out << "\n        </DataArray>\n"
      << "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (size_t t = 0; t < mesh.tets.size(); ++t) out << ' ' << kVtkTetra;
  out << "\n        </DataArray>\n"
      << "      </Cells>\n"
      << "    </Piece>\n"
      << "  </UnstructuredGrid>\n"
      << "</VTKFile>\n";
  return WriteFile(path, out.str());
}

}  // namespace vpm

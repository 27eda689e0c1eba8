#include "server/io/write_displacement_field.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <bit>
#include <sstream>

namespace vpm {
namespace {

std::string MetaImageHeader(const VolumeGeometry& g) {
  std::ostringstream h;
  h.precision(17);
  h << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
    << "CompressedData = False\nTransformMatrix =";
  // MetaIO lists each axis's world direction in turn (ITK's MetaImageIO).
  for (int axis = 0; axis < 3; ++axis) {
    for (int c = 0; c < 3; ++c) h << ' ' << g.direction[axis][c];
  }
  h << "\nOffset = " << g.origin_mm.x << ' ' << g.origin_mm.y << ' ' << g.origin_mm.z
    << "\nCenterOfRotation = 0 0 0\nElementSpacing = " << g.spacing_mm.x << ' '
    << g.spacing_mm.y << ' ' << g.spacing_mm.z << "\nDimSize = " << g.dims[0] << ' '
    << g.dims[1] << ' ' << g.dims[2]
    << "\nElementNumberOfChannels = 3\nElementType = MET_FLOAT\nElementDataFile = LOCAL\n";
  return h.str();
}

std::string NrrdHeader(const VolumeGeometry& g) {
  std::ostringstream h;
  h.precision(17);
  h << "NRRD0004\ntype: float\ndimension: 4\nspace: left-posterior-superior\nsizes: 3 "
    << g.dims[0] << ' ' << g.dims[1] << ' ' << g.dims[2] << "\nspace directions: none";
  for (int axis = 0; axis < 3; ++axis) {
    const glm::dvec3 step = g.direction[axis] * g.spacing_mm[axis];
    h << " (" << step.x << ',' << step.y << ',' << step.z << ')';
  }
  h << "\nkinds: vector domain domain domain\nendian: little\nencoding: raw\nspace origin: ("
    << g.origin_mm.x << ',' << g.origin_mm.y << ',' << g.origin_mm.z << ")\n\n";
  return h.str();
}


}  // namespace

Status WriteDisplacementField(const VolumeGeometry& geometry,
                              const std::vector<glm::vec3>& offsets_lps_mm,
                              const std::filesystem::path& path) {
  if (static_cast<int64_t>(offsets_lps_mm.size()) != geometry.voxel_count()) {
    return absl::InvalidArgumentError(StrCat("displacement field: ", offsets_lps_mm.size(),
                                             " vectors for ", geometry.voxel_count(), " voxels"));
  }
  for (const glm::vec3& d : offsets_lps_mm) {
    if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.z)) {
      return absl::InvalidArgumentError("displacement field: a non-finite offset");
    }
  }
  const std::string name = path.filename().string();
  std::string header;
  if (name.ends_with(".mha")) {
    header = MetaImageHeader(geometry);
  } else if (name.ends_with(".nrrd")) {
    header = NrrdHeader(geometry);
  } else {
    return absl::InvalidArgumentError(
        StrCat("displacement field '", name, "': write .mha or .nrrd"));
  }
  static_assert(std::endian::native == std::endian::little, "written as little-endian floats");
  std::ofstream out(path, std::ios::binary);
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  // glm::vec3 is three packed floats; the data is little-endian x, y, z per
  // voxel, x fastest (little-endian hosts only, as the NIfTI writer).
  out.write(reinterpret_cast<const char*>(offsets_lps_mm.data()),
            static_cast<std::streamsize>(offsets_lps_mm.size() * sizeof(glm::vec3)));
  out.close();
  if (!out) {
    return absl::InternalError(StrCat("displacement field: cannot write '", path.string(), "'"));
  }
  return absl::OkStatus();
}

}  // namespace vpm

// Retrieves one series from a live DICOMweb server through vpm_pacs (the
// client, the multipart parser and the series cache), reads it with vpm's
// DICOM reader, and checks it against
//   - the retrieved slices' own ImagePositionPatient (every slice's
//     position, read from the files with DCMTK): the volume's world position
//     of voxel (0, 0, k) must equal the k-th position along the normal;
//   - the source volume the series was written from: every voxel's world
//     position maps to an integer index of the source, whose value must be
//     equal.
// Run by pacs_orthanc_test.py (not a ctest of its own: it needs the
// Orthanc the script starts). Prints one JSON line of figures; exit 0 when
// every check holds.
//
//   vpm_test_pacs_live_check --url URL --username U --password-file F
//       --study UID --series UID --source VOLUME --cache DIR
#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "server/io/read_dicom_series.h"
#include "server/io/read_volume.h"
#include "server/pacs/dicomweb_client.h"
#include "server/pacs/series_cache.h"

namespace {

namespace fs = std::filesystem;

int Fail(const std::string& what) {
  std::fprintf(stderr, "pacs_live_check: %s\n", what.c_str());
  return 1;
}

std::vector<glm::dvec3> Positions(const fs::path& folder) {
  std::vector<glm::dvec3> out;
  for (const auto& entry : fs::directory_iterator(folder)) {
    DcmFileFormat file;
    if (file.loadFile(entry.path().c_str()).bad()) continue;
    glm::dvec3 p;
    bool ok = true;
    for (int c = 0; c < 3; ++c) {
      Float64 v = 0;
      ok = ok && file.getDataset()->findAndGetFloat64(DCM_ImagePositionPatient, v, c).good();
      p[c] = v;
    }
    if (ok) out.push_back(p);
  }
  return out;
}

// The largest distance, in mm, from slice k of the volume's grid g to the
// k-th file's ImagePositionPatient along the normal; -1 when the counts
// differ.
double MaxPositionErrorMm(const vpm::VolumeGeometry& g, const fs::path& folder) {
  const glm::dvec3 normal = g.direction[2];
  std::vector<glm::dvec3> positions = Positions(folder);
  if (static_cast<int64_t>(positions.size()) != g.dims[2]) return -1.0;
  std::sort(positions.begin(), positions.end(), [&](const glm::dvec3& p, const glm::dvec3& q) {
    return glm::dot(p, normal) < glm::dot(q, normal);
  });
  double worst = 0;
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    const glm::dvec3 world = g.origin_mm + g.direction * glm::dvec3(0, 0, k * g.spacing_mm.z);
    worst = std::max(worst, glm::length(world - positions[k]));
  }
  return worst;
}

// Every voxel of `volume` against the source voxel at the same world point.
struct VoxelComparison {
  double max_index_error = 0, max_value_diff = 0;
  int64_t compared = 0;
  bool outside = false;  // a voxel mapped outside the source
};

VoxelComparison CompareVoxels(const vpm::Volume& volume, const vpm::Volume& source) {
  const auto& g = volume.geometry();
  const auto& s = source.geometry();
  VoxelComparison c;
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const glm::dvec3 world = g.origin_mm + g.direction * (glm::dvec3(i, j, k) * g.spacing_mm);
        const glm::dvec3 index =
            (glm::transpose(s.direction) * (world - s.origin_mm)) / s.spacing_mm;
        const glm::dvec3 r = glm::round(index);
        c.max_index_error = std::max({c.max_index_error, std::abs(index.x - r.x),
                                      std::abs(index.y - r.y), std::abs(index.z - r.z)});
        for (int a = 0; a < 3; ++a) c.outside = c.outside || r[a] < 0 || r[a] >= s.dims[a];
        if (c.outside) return c;
        const double diff =
            std::abs(volume.At(i, j, k) - source.At(int64_t(r.x), int64_t(r.y), int64_t(r.z)));
        c.max_value_diff = std::max(c.max_value_diff, diff);
        ++c.compared;
      }
    }
  }
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  std::map<std::string, std::string> a;
  for (int i = 1; i + 1 < argc; i += 2) a[argv[i]] = argv[i + 1];
  for (const char* key : {"--url", "--study", "--series", "--source", "--cache"}) {
    if (a[key].empty()) return Fail(std::string("missing ") + key);
  }
  vpm::pacs::PacsEndpoint endpoint{
      .name = "live", .dicomweb_url = a["--url"], .username = a["--username"]};
  if (!a["--password-file"].empty()) {
    std::ifstream file(a["--password-file"]);
    std::getline(file, endpoint.password);
  }
  vpm::pacs::DicomwebClient client(endpoint, {});
  auto cache =
      vpm::pacs::SeriesCache::Create({.root = a["--cache"], .max_bytes = int64_t{1} << 30});
  if (!cache.ok()) return Fail(std::string(cache.status().message()));
  const auto start = std::chrono::steady_clock::now();
  int64_t instances = 0;
  auto lease = (*cache)->Open("live", a["--series"], [&](const fs::path& folder, int64_t max) {
    auto got = client.RetrieveSeries(a["--study"], a["--series"], folder, max, -1, {}, {});
    if (got.ok()) instances = got->instances;
    return got.status();
  });
  if (!lease.ok()) return Fail(std::string(lease.status().message()));
  const double retrieve_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  auto volume = vpm::ReadDicomSeries((*lease)->folder, vpm::VolumeLimits{});
  if (!volume.ok()) return Fail(std::string(volume.status().message()));
  auto source = vpm::ReadVolume(a["--source"], vpm::VolumeLimits{});
  if (!source.ok()) return Fail(std::string(source.status().message()));
  const auto& g = volume->geometry();
  const double max_position_error_mm = MaxPositionErrorMm(g, (*lease)->folder);
  if (max_position_error_mm < 0) return Fail("the volume's slices and the files differ in number");
  const VoxelComparison c = CompareVoxels(*volume, *source);
  if (c.outside) return Fail("a voxel maps outside the source");
  std::printf(
      "{\"instances\": %lld, \"bytes\": %lld, \"retrieve_ms\": %.1f, \"dims\": [%lld, %lld, %lld], "
      "\"max_position_error_mm\": %.6f, \"max_index_error\": %.6f, \"voxels_compared\": %lld, "
      "\"max_value_diff\": %g}\n",
      static_cast<long long>(instances), static_cast<long long>((*lease)->bytes), retrieve_ms,
      static_cast<long long>(g.dims[0]), static_cast<long long>(g.dims[1]),
      static_cast<long long>(g.dims[2]), max_position_error_mm, c.max_index_error,
      static_cast<long long>(c.compared), c.max_value_diff);
  const auto& s = source->geometry();
  if (c.compared != s.dims[0] * s.dims[1] * s.dims[2])
    return Fail("not every source voxel compared");
  if (max_position_error_mm > 1e-3) return Fail("slice positions differ from ImagePositionPatient");
  if (c.max_index_error > 1e-3) return Fail("the grid does not line up with the source's");
  if (c.max_value_diff != 0) return Fail("voxel values differ from the source");
  return 0;
}

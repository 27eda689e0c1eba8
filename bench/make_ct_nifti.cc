// Writes a full-size int16 CT as NIfTI for the full-size benchmark
// (bench/full_size.sh): the abdomen phantom rasterized at DIMS (default
// 512 x 512 x 900, the phantom's field of view, so 0.74 x 0.74 x 0.27 mm),
// rounded to integer HU as a scanner stores them. Not committed: 450 MiB.
//   make_ct_nifti OUT.nii [NX NY NZ]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/bench_util.h"
#include "server/io/write_nifti.h"
#include "server/phantom/phantom.h"

using namespace vpm;

int main(int argc, char** argv) {
  if (argc != 2 && argc != 5) {
    std::fprintf(stderr, "usage: make_ct_nifti OUT.nii [NX NY NZ]\n");
    return 2;
  }
  const std::string dims = argc == 5 ? StrCat(argv[2], ",", argv[3], ",", argv[4]) : "512,512,900";
  // The phantom is float (partial volume, noise); this helper alone may hold
  // it past the default budget, once, to make the integer file.
  const Volume phantom = bench::Check(
      MakePhantom(StrCat("abdomen?dims=", dims), UnboundedVolumeLimits()), "phantom");
  const auto floats = phantom.voxels().floats();
  std::vector<int16_t> stored(floats.size());
  for (size_t n = 0; n < floats.size(); ++n) {
    stored[n] = static_cast<int16_t>(std::clamp(std::lround(floats[n]), -32768L, 32767L));
  }
  VoxelValues values = bench::Check(VoxelValues::Int16(std::move(stored), 0), "int16");
  const Volume ct = bench::Check(
      Volume::Create(phantom.geometry(), std::move(values), UnboundedVolumeLimits()), "volume");
  if (const Status written = WriteNifti(ct, argv[1]); !written.ok()) {
    std::fprintf(stderr, "make_ct_nifti: %s\n", std::string(written.message()).c_str());
    return 1;
  }
  std::printf("wrote %s: %s, HU %.0f..%.0f\n", argv[1],
              DescribeVolumeSize(ct.geometry(), ct.encoding()).c_str(), ct.min_value(),
              ct.max_value());
  return 0;
}

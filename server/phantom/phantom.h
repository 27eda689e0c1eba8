// Built-in synthetic volumes ("phantom:NAME?key=value&..." sources).
//
// Spec syntax (what follows "phantom:" in a source string):
//   NAME[?PARAM=VALUE[&PARAM=VALUE...]]
//   size=N            N x N x N voxels (default 256)
//   dims=X,Y,Z        X x Y x Z voxels (not together with size)
//   spacing=A,B,C     voxel size, 0.001 to 1000 mm (default: the phantom's
//                     fixed field of view / dims, so any dims show the same anatomy)
//   seed=S            noise seed, unsigned 64-bit (default 1)
//   noise=SIGMA       Gaussian noise standard deviation, 0 to 10000 HU (default 10)
// Example: "abdomen?size=128&seed=7". docs/PHANTOM.md describes the anatomy.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

inline constexpr uint64_t kDefaultPhantomSeed = 1;
inline constexpr double kDefaultPhantomNoiseHu = 10.0;
inline constexpr int64_t kDefaultPhantomSize = 256;

// A parsed phantom spec.
struct PhantomSpec {
  std::string name;
  std::array<int64_t, 3> dims{kDefaultPhantomSize, kDefaultPhantomSize, kDefaultPhantomSize};
  std::optional<glm::dvec3> spacing_mm;  // unset: field of view / dims
  uint64_t seed = kDefaultPhantomSeed;
  double noise_sigma_hu = kDefaultPhantomNoiseHu;
  int threads = 0;  // worker threads, 0: one per hardware thread (not part of the syntax)
};

// Parses a spec (see the syntax above). Errors: InvalidArgument naming the
// phantom or parameter that is wrong and listing the valid ones. Checks
// syntax only; the size caps are checked by MakePhantom.
Result<PhantomSpec> ParsePhantomSpec(std::string_view spec);

// Builds the phantom `spec` names. Errors: InvalidArgument for a bad spec,
// ResourceExhausted (before allocating anything) when the volume is over
// `limits`. The volume's source is "phantom:" + spec.
Result<Volume> MakePhantom(std::string_view spec, const VolumeLimits& limits);
Result<Volume> MakePhantomFromSpec(const PhantomSpec& spec, const VolumeLimits& limits);

// Names of the built-in phantoms, sorted.
std::vector<std::string> PhantomNames();

}  // namespace vpm

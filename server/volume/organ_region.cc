#include "server/volume/organ_region.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <cmath>
#include <optional>

#include "server/volume/block_average.h"

namespace vpm {
namespace {

// Percentiles p_low and p_high (in [0, 1]) of about 100,000 voxels taken at a
// fixed stride.
std::pair<float, float> RobustRange(const Volume& volume, double p_low, double p_high) {
  const int64_t n = volume.geometry().voxel_count();
  const int64_t stride = std::max<int64_t>(1, n / 100000);
  std::vector<float> sample;
  sample.reserve(static_cast<size_t>(n / stride + 1));
  for (int64_t i = 0; i < n; i += stride) {
    const float v = volume.voxels()[i];
    if (std::isfinite(v)) sample.push_back(v);
  }
  if (sample.empty()) return {0.0f, 0.0f};
  const auto at = [&](double p) {
    auto it = sample.begin() + static_cast<int64_t>(p * double(sample.size() - 1));
    std::nth_element(sample.begin(), it, sample.end());
    return *it;
  };
  return {at(p_low), at(p_high)};
}

// The dominant intensity around `c` (the 5 x 5 x 5 voxels, clamped at the
// edges): the value with the most neighbours within +-band, refined to the
// median of those neighbours. A click near a hilum or on a partial-volume
// voxel still finds the organ's own intensity.
float DominantIntensity(const Volume& volume, const std::array<int64_t, 3>& c, float band) {
  std::vector<float> values;
  for (int64_t k = c[2] - 2; k <= c[2] + 2; ++k)
    for (int64_t j = c[1] - 2; j <= c[1] + 2; ++j)
      for (int64_t i = c[0] - 2; i <= c[0] + 2; ++i) {
        const float v = volume.AtClamped(i, j, k);
        if (std::isfinite(v)) values.push_back(v);
      }
  if (values.empty()) return 0.0f;
  const float centre = volume.AtClamped(c[0], c[1], c[2]);
  float best = values.front();
  size_t best_count = 0;
  for (float v : values) {
    const size_t count = std::count_if(values.begin(), values.end(),
                                       [&](float w) { return std::abs(w - v) <= band; });
    if (count > best_count ||
        (count == best_count && std::abs(v - centre) < std::abs(best - centre))) {
      best = v, best_count = count;
    }
  }
  std::vector<float> near;
  for (float v : values) {
    if (std::abs(v - best) <= band) near.push_back(v);
  }
  auto mid = near.begin() + near.size() / 2;
  std::nth_element(near.begin(), mid, near.end());
  return *mid;
}

// A dense mask over the box [lo, hi] (voxel indices, inclusive).
struct BoxMask {
  std::array<int64_t, 3> lo{}, size{};
  std::vector<uint8_t> bits;
  int64_t Index(int64_t i, int64_t j, int64_t k) const {
    return (i - lo[0]) + size[0] * ((j - lo[1]) + size[1] * (k - lo[2]));
  }
  bool Inside(int64_t i, int64_t j, int64_t k) const {
    return i >= lo[0] && j >= lo[1] && k >= lo[2] && i < lo[0] + size[0] &&
           j < lo[1] + size[1] && k < lo[2] + size[2];
  }
  bool At(int64_t i, int64_t j, int64_t k) const { return Inside(i, j, k) && bits[Index(i, j, k)]; }
};

constexpr int kSteps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};

// `mask` cut to the box [lo, hi] (the bounding box of its set voxels) and
// one voxel around.
BoxMask Crop(const BoxMask& mask, const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& hi) {
  BoxMask out;
  for (int a = 0; a < 3; ++a) {
    out.lo[a] = lo[a] - 1;
    out.size[a] = hi[a] - lo[a] + 3;
  }
  out.bits.assign(out.size[0] * out.size[1] * out.size[2], 0);
  const int64_t row = hi[0] - lo[0] + 1;
  for (int64_t k = lo[2]; k <= hi[2]; ++k)
    for (int64_t j = lo[1]; j <= hi[1]; ++j)
      std::copy_n(&mask.bits[mask.Index(lo[0], j, k)], row, &out.bits[out.Index(lo[0], j, k)]);
  return out;
}

// The face-connected voxels of `box` reachable from `seed` through voxels
// `accept` takes (none when it does not take the seed), in `box`'s box.
// `lo`/`hi` get the bounding box of the set voxels (unchanged when none).
// A scanline fill: each popped voxel is widened to the whole run along i it
// lies in, and the rows beside the run (j +- 1, k +- 1) get one seed per run
// of theirs, so the volume and the mask are read along memory.
template <typename Accept>
BoxMask Grow(const BoxMask& box, const std::array<int64_t, 3>& seed, const Accept& accept,
             std::array<int64_t, 3>& lo, std::array<int64_t, 3>& hi) {
  BoxMask out = box;
  out.bits.assign(box.size[0] * box.size[1] * box.size[2], 0);
  if (!accept(seed[0], seed[1], seed[2])) return out;
  lo = seed, hi = seed;
  const int64_t i_lo = box.lo[0], i_hi = box.lo[0] + box.size[0] - 1;
  const auto open = [&](int64_t i, int64_t j, int64_t k) {
    return !out.bits[out.Index(i, j, k)] && accept(i, j, k);
  };
  std::vector<std::array<int64_t, 3>> stack{seed};
  while (!stack.empty()) {
    const auto [i, j, k] = stack.back();
    stack.pop_back();
    if (!open(i, j, k)) continue;  // filled since it was pushed
    int64_t l = i, r = i;
    while (l > i_lo && open(l - 1, j, k)) --l;
    while (r < i_hi && open(r + 1, j, k)) ++r;
    std::fill_n(&out.bits[out.Index(l, j, k)], r - l + 1, uint8_t{1});
    lo = {std::min(lo[0], l), std::min(lo[1], j), std::min(lo[2], k)};
    hi = {std::max(hi[0], r), std::max(hi[1], j), std::max(hi[2], k)};
    for (const auto& st : kSteps) {
      if (st[0] != 0) continue;
      const int64_t b = j + st[1], c = k + st[2];
      if (!out.Inside(l, b, c)) continue;
      bool in_run = false;
      for (int64_t x = l; x <= r; ++x) {
        const bool take = open(x, b, c);
        if (take && !in_run) stack.push_back({x, b, c});
        in_run = take;
      }
    }
  }
  return out;
}

// Grow, cut to the bounding box of the set voxels and one voxel around, so
// every set voxel has its six neighbours inside the box (Morph relies on
// it); the whole box, all unset, when the seed is not taken.
template <typename Accept>
BoxMask GrowCropped(const BoxMask& box, const std::array<int64_t, 3>& seed, const Accept& accept) {
  std::array<int64_t, 3> lo{}, hi = {-1, -1, -1};
  BoxMask grown = Grow(box, seed, accept, lo, hi);
  return hi[0] < 0 ? grown : Crop(grown, lo, hi);
}

// The face-connected component of `allowed` through `seed` (empty if the
// seed is not allowed), in `allowed`'s box.
BoxMask Component(const BoxMask& allowed, const std::array<int64_t, 3>& seed) {
  std::array<int64_t, 3> lo{}, hi{};
  return Grow(allowed, seed, [&](int64_t i, int64_t j, int64_t k) { return allowed.At(i, j, k); },
              lo, hi);
}

// The largest face-connected component of `mask` with a voxel within
// `reach` voxels (Chebyshev) of `c`; none when no such voxel is set.
std::optional<BoxMask> LargestComponentNear(const BoxMask& mask, const std::array<int64_t, 3>& c,
                                            int reach) {
  std::optional<BoxMask> best;
  int64_t best_count = 0;
  for (int64_t dk = -reach; dk <= reach; ++dk)
    for (int64_t dj = -reach; dj <= reach; ++dj)
      for (int64_t di = -reach; di <= reach; ++di) {
        const std::array<int64_t, 3> at{c[0] + di, c[1] + dj, c[2] + dk};
        if (!mask.At(at[0], at[1], at[2])) continue;
        if (best && best->At(at[0], at[1], at[2])) continue;  // already that one
        BoxMask component = Component(mask, at);
        const int64_t count = std::count(component.bits.begin(), component.bits.end(), 1);
        if (count > best_count) best = std::move(component), best_count = count;
      }
  return best;
}

// One face-connected erosion (grow = false) or dilation within `limit`
// (same box as `in`). Erosion keeps a set voxel while at least `keep` of its
// six neighbours are set (6: all; 5: a voxel with one neighbour missing, as
// noise leaves inside an organ, stays); dilation sets an unset voxel of
// `limit` beside a set one. Only a set voxel can erode and only an unset one
// inside `limit` can grow, and each of those has its six neighbours inside
// the box (Grow's margin), so they are read by linear offsets.
BoxMask Morph(const BoxMask& in, bool grow, const BoxMask& limit, int keep = 6) {
  BoxMask out = in;
  const int64_t sx = in.size[0], sxy = in.size[0] * in.size[1];
  const int64_t offsets[6] = {1, -1, sx, -sx, sxy, -sxy};
  const uint8_t* bits = in.bits.data();
  const int64_t n = static_cast<int64_t>(in.bits.size());
  for (int64_t x = 0; x < n; ++x) {
    if (grow ? (bits[x] || !limit.bits[x]) : !bits[x]) continue;  // out = in
    if (grow) {
      for (int64_t o : offsets) {
        if (bits[x + o]) {
          out.bits[x] = 1;
          break;
        }
      }
      continue;
    }
    int set = 0;
    for (int64_t o : offsets) set += bits[x + o] != 0;
    if (set < keep) out.bits[x] = 0;
  }
  return out;
}

// The flood's start: the seed, or where the seed's voxel is off the
// organ's intensity (a stone, partial volume), the accepted voxel nearest to
// it within two voxels.
template <typename Accept>
std::array<int64_t, 3> FloodStart(const std::array<int64_t, 3>& seed, const Accept& accept) {
  std::array<int64_t, 3> start = seed;
  int64_t best_d2 = accept(seed[0], seed[1], seed[2]) ? 0 : -1;
  for (int64_t dk = -2; dk <= 2 && best_d2 != 0; ++dk)
    for (int64_t dj = -2; dj <= 2; ++dj)
      for (int64_t di = -2; di <= 2; ++di) {
        const int64_t d2 = di * di + dj * dj + dk * dk;
        if ((best_d2 < 0 || d2 < best_d2) && accept(seed[0] + di, seed[1] + dj, seed[2] + dk)) {
          start = {seed[0] + di, seed[1] + dj, seed[2] + dk};
          best_d2 = d2;
        }
      }
  return start;
}

int64_t CountSet(const BoxMask& mask) { return std::count(mask.bits.begin(), mask.bits.end(), 1); }

// A morphological opening of `grown` by `voxels` (erosions keeping voxels
// with `keep` of 6 neighbours set, then as many dilations within it),
// anchored at the seed: the largest eroded component within two voxels of
// it; none where the seed's whole neighbourhood erodes away.
std::optional<BoxMask> Open(const BoxMask& grown, int voxels, int keep,
                            const std::array<int64_t, 3>& seed) {
  BoxMask core = grown;
  for (int n = 0; n < voxels; ++n) core = Morph(core, false, grown, keep);
  // The seed itself may erode away (next to a hilum's fat, in a thin
  // part): the largest core component within two voxels stands for it.
  std::optional<BoxMask> anchored = LargestComponentNear(core, seed, 2);
  if (!anchored) return std::nullopt;
  for (int n = 0; n < voxels; ++n) *anchored = Morph(*anchored, true, grown);
  return anchored;
}

// The opening of `grown` at the seed (Open with every neighbour needed).
// Where it keeps less than kNoiseBrokenShare of what the flood grew, noise
// about the window's size has broken the organ's core into specks (too few
// cells have all six neighbours in the window, while the flood went on
// through those the noise let in), and the erosion that keeps a cell with
// one neighbour missing is used instead where it keeps more (*lenient set).
// Where the seed's whole neighbourhood erodes away in both (a thin
// structure), `grown` is kept as it is.
constexpr double kNoiseBrokenShare = 0.01;

BoxMask OpenAtSeed(BoxMask grown, int voxels, const std::array<int64_t, 3>& seed, bool* lenient) {
  std::optional<BoxMask> opened = Open(grown, voxels, 6, seed);
  const int64_t opened_count = opened ? CountSet(*opened) : 0;
  if (double(opened_count) < kNoiseBrokenShare * double(CountSet(grown))) {
    std::optional<BoxMask> lenient_opened = Open(grown, voxels, 5, seed);
    if (lenient_opened && CountSet(*lenient_opened) > opened_count) {
      *lenient = true;
      return *std::move(lenient_opened);
    }
  }
  return opened ? *std::move(opened) : grown;
}

// The grown voxels' linear indices into region.voxels, in (k, j, i) order
// (ascending), and whether any lies within a voxel of the bound
// (region.reached_bound).
void CollectVoxels(const Volume& volume, const BoxMask& grown, const glm::dvec3& index,
                   double max_radius_mm, OrganRegion& region) {
  const glm::dvec3 s = volume.spacing_mm();
  const double bound = max_radius_mm - std::max({s.x, s.y, s.z});
  const double bound2 = bound > 0.0 ? bound * bound : -1.0;
  for (int64_t k = grown.lo[2]; k < grown.lo[2] + grown.size[2]; ++k) {
    for (int64_t j = grown.lo[1]; j < grown.lo[1] + grown.size[1]; ++j) {
      const uint8_t* row = &grown.bits[grown.Index(grown.lo[0], j, k)];
      for (int64_t i = grown.lo[0]; i < grown.lo[0] + grown.size[0]; ++i) {
        if (!row[i - grown.lo[0]]) continue;
        region.voxels.push_back(volume.LinearIndex(i, j, k));
        const glm::dvec3 d = (glm::dvec3(i, j, k) - glm::dvec3(index)) * s;
        region.reached_bound |= glm::dot(d, d) > bound2;
      }
    }
  }
}

// The region grown on `grid` (the working grid's volume) from seed_mm
// (its physical voxel space), with region.window set: region.reference,
// voxels, reached_bound, volume_mm3 and lenient_opening.
void GrowOnGrid(const Volume& grid, const glm::dvec3& seed_mm, const OrganRegionParams& params,
                OrganRegion& region) {
  const glm::dvec3 index = glm::round(grid.geometry().PhysicalToIndex(seed_mm));
  const auto& dims = grid.dims();
  const std::array<int64_t, 3> seed{int64_t(index.x), int64_t(index.y), int64_t(index.z)};
  region.reference = DominantIntensity(grid, seed, 0.5f * region.window);
  const glm::dvec3 s = grid.spacing_mm();
  BoxMask box;  // the bound's box
  for (int a = 0; a < 3; ++a) {
    const auto reach = static_cast<int64_t>(std::ceil(params.max_radius_mm / s[a]));
    box.lo[a] = std::max<int64_t>(0, seed[a] - reach);
    box.size[a] = std::min<int64_t>(dims[a] - 1, seed[a] + reach) - box.lo[a] + 1;
  }
  const double r2 = params.max_radius_mm * params.max_radius_mm;
  const auto accept = [&](int64_t i, int64_t j, int64_t k) {
    const glm::dvec3 d = (glm::dvec3(i, j, k) - glm::dvec3(index)) * s;
    return box.Inside(i, j, k) && glm::dot(d, d) <= r2 &&
           std::abs(grid.At(i, j, k) - region.reference) <= region.window;
  };
  const std::array<int64_t, 3> start = FloodStart(seed, accept);
  BoxMask grown = GrowCropped(box, start, accept);
  if (params.opening_voxels > 0) {
    grown = OpenAtSeed(std::move(grown), params.opening_voxels, seed, &region.lenient_opening);
  }
  CollectVoxels(grid, grown, index, params.max_radius_mm, region);
  if (region.voxels.empty()) region.voxels.push_back(grid.LinearIndex(seed[0], seed[1], seed[2]));
  region.volume_mm3 = double(region.voxels.size()) * s.x * s.y * s.z;
}

Status CheckParams(const glm::dvec3& seed_mm, const OrganRegionParams& params) {
  if (!std::isfinite(seed_mm.x) || !std::isfinite(seed_mm.y) || !std::isfinite(seed_mm.z)) {
    return absl::InvalidArgumentError("organ seed must be finite");
  }
  if (!(params.max_radius_mm > 0.0) || !std::isfinite(params.max_radius_mm) ||
      !(params.window_fraction >= 0.0) || params.opening_voxels < 0 || params.opening_voxels > 4 ||
      !(params.working_spacing_mm >= 0.0) || !std::isfinite(params.working_spacing_mm)) {
    return absl::InvalidArgumentError("organ region: bad parameters");
  }
  return absl::OkStatus();
}

// The region on the working grid of `factor` (not all 1): the bound's box
// averaged in blocks, one cell more each side, the seed's voxel at the
// middle of its cell; region.window set.
Status GrowOnWorkingGrid(const Volume& volume, const glm::dvec3& seed_mm,
                         const std::array<int64_t, 3>& factor, const OrganRegionParams& params,
                         OrganRegion& region) {
  const glm::dvec3 s = volume.spacing_mm();
  const glm::dvec3 index = glm::round(volume.geometry().PhysicalToIndex(seed_mm));
  std::array<int64_t, 3> lo{}, size{};
  for (int a = 0; a < 3; ++a) {
    const double cell_mm = double(factor[a]) * s[a];
    const auto reach = static_cast<int64_t>(std::ceil(params.max_radius_mm / cell_mm)) + 1;
    lo[a] = int64_t(index[a]) - factor[a] / 2 - reach * factor[a];
    size[a] = (2 * reach + 1) * factor[a];
  }
  ASSIGN_OR_RETURN(const Volume grid, BlockAverage(volume, lo, size, factor, region.grid));
  const glm::dvec3 last =
      glm::dvec3(grid.dims()[0] - 1, grid.dims()[1] - 1, grid.dims()[2] - 1) * grid.spacing_mm();
  const glm::dvec3 grid_seed =
      glm::clamp(region.grid.VolumeToGrid(seed_mm, s), glm::dvec3(0.0), last);
  GrowOnGrid(grid, grid_seed, params, region);
  return absl::OkStatus();
}

}  // namespace

bool OrganRegion::Contains(int64_t i, int64_t j, int64_t k) const {
  std::array<int64_t, 3> c{};
  if (!grid.CellOf(i, j, k, c)) return false;
  const int64_t linear = c[0] + grid.dims[0] * (c[1] + grid.dims[1] * c[2]);
  return std::binary_search(voxels.begin(), voxels.end(), linear);
}

Result<OrganRegion> GrowOrganRegion(const Volume& volume, const glm::dvec3& seed_mm,
                                    const OrganRegionParams& params) {
  RETURN_IF_ERROR(CheckParams(seed_mm, params));
  const glm::dvec3 index = glm::round(volume.geometry().PhysicalToIndex(seed_mm));
  const auto& dims = volume.dims();
  for (int a = 0; a < 3; ++a) {
    if (index[a] < 0 || index[a] >= double(dims[a])) {
      return absl::OutOfRangeError("organ seed lies outside the volume");
    }
  }
  OrganRegion region;
  const auto [low, high] = RobustRange(volume, 0.02, 0.98);
  region.window = static_cast<float>(params.window_fraction * double(high - low));
  const glm::dvec3 s = volume.spacing_mm();
  // A bound past the volume's diagonal and a few cells bounds nothing more;
  // held there, the boxes stay small integers whatever was asked.
  OrganRegionParams bounded = params;
  bounded.max_radius_mm =
      std::min(params.max_radius_mm,
               glm::length(volume.geometry().extent_mm()) +
                   4.0 * std::max(params.working_spacing_mm, std::max({s.x, s.y, s.z})));
  const std::array<int64_t, 3> factor = BlockFactor(s, params.working_spacing_mm);
  if (factor == std::array<int64_t, 3>{1, 1, 1}) {
    region.grid.dims = dims;
    GrowOnGrid(volume, seed_mm, bounded, region);
  } else {
    RETURN_IF_ERROR(GrowOnWorkingGrid(volume, seed_mm, factor, bounded, region));
  }
  return region;
}

}  // namespace vpm

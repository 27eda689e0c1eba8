#include "server/phantom/phantom_raster.h"

#include <algorithm>
#include <atomic>
#include <thread>

#include "server/phantom/phantom_noise.h"

namespace vpm::phantom {
namespace {

constexpr int kCrossSectionSupersampling = 4;  // per axis, per pixel

// The box-filtered cross-section, one value per (i, j) pixel.
struct CrossSectionMaps {
  std::vector<float> base_hu;          // mean of the non-bowel tissue values
  std::vector<float> bowel_frac;       // fraction of the pixel taking the bowel texture
  std::vector<float> cavity_frac;      // fraction of the pixel inside the cavity
  std::vector<IndexRange> bowel_rows;  // per j: the i range where bowel_frac > 0
};

// Runs body(item) for item in [0, count) on `threads` threads; items are
// handed out one by one, so the split never affects what an item computes.
template <typename Body>
void ParallelFor(int64_t count, int threads, Body body) {
  std::atomic<int64_t> next{0};
  auto worker = [&] {
    for (int64_t item = next++; item < count; item = next++) body(item);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
}

void FillCrossSectionRow(const Scene& scene, const VolumeGeometry& g, int64_t j,
                         CrossSectionMaps& maps) {
  const int64_t nx = g.dims[0];
  constexpr int s = kCrossSectionSupersampling;
  constexpr float kWeight = 1.0f / (s * s);
  IndexRange bowel_range{static_cast<size_t>(nx), 0};
  for (int64_t i = 0; i < nx; ++i) {
    float hu = 0.0f;
    float bowel = 0.0f;
    float cavity = 0.0f;
    for (int b = 0; b < s; ++b) {
      const double y =
          g.origin_mm.y + (static_cast<double>(j) + (b + 0.5) / s - 0.5) * g.spacing_mm.y;
      for (int a = 0; a < s; ++a) {
        const double x =
            g.origin_mm.x + (static_cast<double>(i) + (a + 0.5) / s - 0.5) * g.spacing_mm.x;
        const CrossSectionSample sample = scene.cross_section(x, y);
        if (sample.bowel) {
          bowel += kWeight;
        } else {
          hu += kWeight * sample.hu;
        }
        if (sample.cavity) cavity += kWeight;
      }
    }
    const size_t at = static_cast<size_t>(j * nx + i);
    maps.base_hu[at] = hu;
    maps.bowel_frac[at] = bowel;
    maps.cavity_frac[at] = cavity;
    if (bowel > 0.0f) {
      bowel_range.begin = std::min(bowel_range.begin, static_cast<size_t>(i));
      bowel_range.end = static_cast<size_t>(i + 1);
    }
  }
  maps.bowel_rows[static_cast<size_t>(j)] = bowel_range;
}

CrossSectionMaps MakeCrossSectionMaps(const Scene& scene, const VolumeGeometry& g, int threads) {
  const size_t pixels = static_cast<size_t>(g.dims[0] * g.dims[1]);
  CrossSectionMaps maps{std::vector<float>(pixels), std::vector<float>(pixels),
                        std::vector<float>(pixels),
                        std::vector<IndexRange>(static_cast<size_t>(g.dims[1]))};
  ParallelFor(g.dims[1], threads, [&](int64_t j) { FillCrossSectionRow(scene, g, j, maps); });
  return maps;
}

// Everything one thread needs to paint rows.
class RowPainter {
 public:
  RowPainter(const Scene& scene, const VolumeGeometry& g, const CrossSectionMaps& maps)
      : scene_(scene), g_(g), maps_(maps), nx_(static_cast<size_t>(g.dims[0])) {
    const glm::dvec3& s = g.spacing_mm;
    blend_width_mm_ = (s.x + s.y + s.z) / 3.0;
    distance_.resize(nx_);
    texture_.resize(nx_);
  }

  // Primitives whose bounds (plus blend reach) meet the plane z = z_mm.
  void BeginSlice(double z_mm) {
    active_.clear();
    for (const Primitive& p : scene_.primitives) {
      const Box3 box = p.shape->Bounds().Expanded(Reach(p));
      if (z_mm >= box.lo.z && z_mm <= box.hi.z) active_.push_back(&p);
    }
  }

  void PaintRow(int64_t j, double z_mm, std::span<float> row) {
    const SampleRow sample_row{g_.origin_mm.x, g_.spacing_mm.x,
                               g_.origin_mm.y + static_cast<double>(j) * g_.spacing_mm.y, z_mm};
    const size_t map_row = static_cast<size_t>(j) * nx_;
    std::copy_n(maps_.base_hu.begin() + static_cast<std::ptrdiff_t>(map_row), nx_, row.begin());
    const IndexRange bowel = maps_.bowel_rows[static_cast<size_t>(j)];
    if (!bowel.empty() && scene_.bowel) {
      std::span<float> texture(texture_.data() + bowel.begin, bowel.end - bowel.begin);
      scene_.bowel(sample_row.Shifted(bowel.begin), blend_width_mm_, texture);
      for (size_t i = bowel.begin; i < bowel.end; ++i) {
        row[i] += maps_.bowel_frac[map_row + i] * texture_[i];
      }
    }
    for (const Primitive* p : active_) PaintPrimitive(*p, sample_row, map_row, row);
  }

 private:
  double Reach(const Primitive& p) const {
    double deepest = 0.0;
    for (const TissueLayer& layer : p.layers) deepest = std::max(deepest, layer.inset_mm);
    return 0.5 * blend_width_mm_ + deepest;
  }

  void PaintPrimitive(const Primitive& p, const SampleRow& sample_row, size_t map_row,
                      std::span<float> row) {
    const double reach = Reach(p);
    const Box3 box = p.shape->Bounds().Expanded(reach);
    if (!box.CoversYZ(sample_row.y_mm, sample_row.z_mm)) return;
    const IndexRange range = RowRangeInBox(box, sample_row, nx_);
    if (range.empty()) return;
    std::span<float> distance(distance_.data() + range.begin, range.end - range.begin);
    p.shape->RowDistance(sample_row.Shifted(range.begin), reach, distance);
    const float inv_width = static_cast<float>(1.0 / blend_width_mm_);
    for (const TissueLayer& layer : p.layers) {
      const float inset = static_cast<float>(layer.inset_mm);
      for (size_t n = 0; n < distance.size(); ++n) {
        float coverage = std::clamp(0.5f - (distance[n] + inset) * inv_width, 0.0f, 1.0f);
        if (coverage == 0.0f) continue;
        const size_t i = range.begin + n;
        if (p.clip_to_cavity) coverage *= maps_.cavity_frac[map_row + i];
        row[i] += coverage * (layer.hu - row[i]);
      }
    }
  }

  const Scene& scene_;
  const VolumeGeometry& g_;
  const CrossSectionMaps& maps_;
  size_t nx_;
  double blend_width_mm_ = 1.0;
  std::vector<const Primitive*> active_;
  std::vector<float> distance_;
  std::vector<float> texture_;
};

}  // namespace

void Rasterize(const Scene& scene, const VolumeGeometry& g, const RasterOptions& options,
               std::span<float> values_hu) {
  int threads =
      options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = static_cast<int>(std::clamp<int64_t>(threads, 1, std::min<int64_t>(64, g.dims[2])));
  const CrossSectionMaps maps = MakeCrossSectionMaps(scene, g, threads);
  const int64_t nx = g.dims[0];
  const int64_t ny = g.dims[1];
  ParallelFor(g.dims[2], threads, [&](int64_t k) {
    // One painter per slice keeps the threads free of shared scratch.
    RowPainter painter(scene, g, maps);
    const double z_mm = g.origin_mm.z + static_cast<double>(k) * g.spacing_mm.z;
    painter.BeginSlice(z_mm);
    for (int64_t j = 0; j < ny; ++j) {
      const int64_t first = nx * (j + ny * k);
      std::span<float> row = values_hu.subspan(static_cast<size_t>(first), static_cast<size_t>(nx));
      painter.PaintRow(j, z_mm, row);
      AddGaussianNoise(options.noise_seed, static_cast<uint64_t>(first), options.noise_sigma_hu,
                       row);
    }
  });
}

}  // namespace vpm::phantom

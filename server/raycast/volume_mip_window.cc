#include "server/raycast/volume_mip_window.h"

#include <algorithm>
#include <cmath>

namespace vpm {

std::vector<float> SampleVolumeValues(const Volume& volume, double floor) {
  const VoxelValues& values = volume.voxels();
  const int64_t count = values.size();
  const int64_t stride = std::max<int64_t>(1, count >> 20);
  std::vector<float> sample;
  sample.reserve(static_cast<size_t>(count / stride + 1));
  for (int64_t n = 0; n < count; n += stride) {
    const float v = values[n];
    if (v > floor) sample.push_back(v);
  }
  return sample;
}

std::vector<double> Percentiles(std::vector<float>& values, const std::vector<double>& p) {
  std::vector<double> out;
  for (double q : p) {
    if (values.empty()) {
      out.push_back(0.0);
      continue;
    }
    // nth_element, not a sort: O(n) per percentile (a million values: a few ms).
    const double pos = q / 100.0 * double(values.size() - 1);
    const size_t lo = size_t(std::floor(pos));
    std::nth_element(values.begin(), values.begin() + lo, values.end());
    const float a = values[lo];
    const float b = lo + 1 < values.size()
                        ? *std::min_element(values.begin() + lo + 1, values.end())
                        : a;
    out.push_back(a + (pos - double(lo)) * (b - a));
  }
  return out;
}

MipWindow VolumeMipWindow(const Volume& volume) {
  const bool ct = IsCtInHu(volume);
  std::vector<float> sample = SampleVolumeValues(volume, ct ? kCtAirCeilingHu : -INFINITY);
  if (sample.empty()) sample = SampleVolumeValues(volume, -INFINITY);  // CT that is all air
  const std::vector<double> p =
      Percentiles(sample, {kMipWindowLowPercentile, kMipWindowHighPercentile});
  const double black = p[0];
  const double white = std::max(p[1], black + 1e-3);
  return {0.5 * (black + white), white - black};
}

}  // namespace vpm

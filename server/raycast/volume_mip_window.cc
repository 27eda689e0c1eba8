#include "server/raycast/volume_mip_window.h"

#include <algorithm>
#include <cmath>

namespace vpm {

bool IsCtInHu(const Volume& volume) { return volume.min_value() < kCtAirCeilingHu; }

std::vector<float> SampleVolumeValues(const Volume& volume, double floor) {
  const auto values = volume.values();
  const size_t stride = std::max<size_t>(1, values.size() >> 20);
  std::vector<float> sample;
  sample.reserve(values.size() / stride + 1);
  for (size_t n = 0; n < values.size(); n += stride) {
    if (values[n] > floor) sample.push_back(values[n]);
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

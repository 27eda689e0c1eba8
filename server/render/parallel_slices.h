// Runs body(k) for k in [0, count) on `threads` threads (contiguous blocks),
// for the CPU references that process a volume or grid slice by slice.
#pragma once

#include <algorithm>
#include <cstdint>
#include <thread>
#include <vector>

namespace vpm {

template <typename Body>
void ParallelSlices(int64_t count, int threads, const Body& body) {
  const int64_t workers = std::clamp<int64_t>(threads, 1, std::max<int64_t>(count, 1));
  if (workers == 1) {
    for (int64_t k = 0; k < count; ++k) body(k);
    return;
  }
  std::vector<std::thread> pool;
  for (int64_t w = 0; w < workers; ++w) {
    pool.emplace_back([&, w] {
      for (int64_t k = count * w / workers; k < count * (w + 1) / workers; ++k) body(k);
    });
  }
  for (std::thread& t : pool) t.join();
}

}  // namespace vpm

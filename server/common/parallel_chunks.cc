#include "server/common/parallel_chunks.h"

#include <thread>
#include <vector>

namespace vpm {

void ParallelChunks(int parts, int64_t n,
                    const std::function<void(int64_t begin, int64_t end, int part)>& fn) {
  if (parts <= 1 || n < parts) {
    fn(0, n, 0);
    return;
  }
  std::vector<std::thread> workers;
  workers.reserve(parts - 1);
  for (int p = 1; p < parts; ++p) {
    workers.emplace_back(fn, n * p / parts, n * (p + 1) / parts, p);
  }
  fn(0, n / parts, 0);
  for (std::thread& worker : workers) worker.join();
}

}  // namespace vpm

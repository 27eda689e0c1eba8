// Splitting a loop over elements between a few threads.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>

namespace vpm {

// Runs fn(begin, end, part) for `parts` contiguous chunks of [0, n) that
// cover it in order, part 0 on the calling thread and the others on threads
// of their own; returns when all are done. parts <= 1 (or n < parts) runs
// fn(0, n, 0) on the caller. Thread start-up costs ~20-50 us, so callers
// split only loops of a millisecond or more.
void ParallelChunks(int parts, int64_t n,
                    const std::function<void(int64_t begin, int64_t end, int part)>& fn);

// Runs body(k) for every k in [0, count) on up to `threads` threads, in
// contiguous blocks: for the CPU references that process a volume or a grid
// slice by slice.
template <typename Body>
void ParallelSlices(int64_t count, int threads, const Body& body) {
  const int parts = static_cast<int>(std::clamp<int64_t>(threads, 1, std::max<int64_t>(count, 1)));
  ParallelChunks(parts, count, [&](int64_t begin, int64_t end, int) {
    for (int64_t k = begin; k < end; ++k) body(k);
  });
}

}  // namespace vpm

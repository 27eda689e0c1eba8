// Splitting a loop over elements between a few threads.
#pragma once

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

}  // namespace vpm

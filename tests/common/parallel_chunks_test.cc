#include <atomic>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "server/common/parallel_chunks.h"

namespace vpm {
namespace {

TEST(ParallelChunks, ChunksCoverTheRangeOnceInOrderOfParts) {
  for (int parts : {1, 2, 3, 7}) {
    for (int64_t n : {0, 1, 5, 100}) {
      std::vector<int> hits(n, 0);
      std::vector<int64_t> begins(parts, -1);
      ParallelChunks(parts, n, [&](int64_t begin, int64_t end, int part) {
        begins[part] = begin;
        for (int64_t k = begin; k < end; ++k) ++hits[k];
      });
      for (int64_t k = 0; k < n; ++k) EXPECT_EQ(hits[k], 1) << parts << " parts, n " << n;
      EXPECT_EQ(begins[0], 0);
    }
  }
}

TEST(ParallelSlices, VisitsEverySliceOnceWithMoreThreadsThanSlices) {
  std::vector<std::atomic<int>> hits(3);
  ParallelSlices(3, 8, [&](int64_t k) { ++hits[k]; });
  for (auto& h : hits) EXPECT_EQ(h.load(), 1);
}

}  // namespace
}  // namespace vpm

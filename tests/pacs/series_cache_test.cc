#include "server/pacs/series_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <thread>

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

class SeriesCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("vpm-cache-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  std::unique_ptr<SeriesCache> Make(int64_t max_bytes) {
    auto cache = SeriesCache::Create({.root = root_, .max_bytes = max_bytes});
    EXPECT_TRUE(cache.ok()) << cache.status();
    return *std::move(cache);
  }
  // A fetch writing `files` files of `bytes` bytes each, counting its calls.
  SeriesCache::Fetch Writer(int files, int64_t bytes, std::atomic<int>* calls, int sleep_ms = 0) {
    return [=](const fs::path& folder, int64_t) {
      ++*calls;
      std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
      for (int i = 0; i < files; ++i) {
        std::ofstream(folder / (std::to_string(i) + ".dcm")) << std::string(bytes, 'x');
      }
      return absl::OkStatus();
    };
  }
  int TempFolders() {
    int n = 0;
    for (const auto& e : fs::directory_iterator(root_)) {
      n += e.path().filename().string().starts_with(".tmp-");
    }
    return n;
  }
  fs::path root_;
};

TEST_F(SeriesCacheTest, SecondOpenIsAHit) {
  auto cache = Make(1 << 20);
  std::atomic<int> calls{0};
  auto first = cache->Open("pacs1", "1.2.3", Writer(3, 100, &calls));
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_FALSE((*first)->hit);
  EXPECT_EQ((*first)->bytes, 300);
  EXPECT_TRUE(fs::exists((*first)->folder / "2.dcm"));
  auto second = cache->Open("pacs1", "1.2.3", Writer(3, 100, &calls));
  ASSERT_TRUE(second.ok());
  EXPECT_TRUE((*second)->hit);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(cache->stats().hits, 1);
  EXPECT_EQ(cache->stats().fetches, 1);
}

TEST_F(SeriesCacheTest, ConcurrentOpensFetchOnce) {
  auto cache = Make(1 << 20);
  std::atomic<int> calls{0};
  std::vector<std::thread> threads;
  std::atomic<int> ok{0};
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back(
        [&] { ok += cache->Open("pacs1", "1.2.3", Writer(2, 10, &calls, 200)).ok(); });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(ok, 4);
  EXPECT_EQ(calls, 1);
}

TEST_F(SeriesCacheTest, FailedFetchLeavesNothing) {
  auto cache = Make(1 << 20);
  auto failed = cache->Open("pacs1", "1.2.3", [](const fs::path& folder, int64_t) {
    std::ofstream(folder / "half.dcm") << "partial";
    return absl::InvalidArgumentError("multipart: truncated");
  });
  EXPECT_TRUE(absl::IsInvalidArgument(failed.status()));
  EXPECT_EQ(cache->stats().entries, 0);
  EXPECT_EQ(TempFolders(), 0);
  EXPECT_FALSE(fs::exists(root_ / "pacs1" / "1.2.3"));
}

TEST_F(SeriesCacheTest, EvictsLeastRecentlyUsedUnderBudget) {
  auto cache = Make(1000);
  std::atomic<int> calls{0};
  ASSERT_TRUE(cache->Open("p", "1.1", Writer(4, 100, &calls)).ok());  // 400
  ASSERT_TRUE(cache->Open("p", "1.2", Writer(4, 100, &calls)).ok());  // 800
  ASSERT_TRUE(cache->Open("p", "1.1", Writer(4, 100, &calls)).ok());  // 1.1 used again
  ASSERT_TRUE(cache->Open("p", "1.3", Writer(4, 100, &calls)).ok());  // evicts 1.2
  EXPECT_TRUE(fs::exists(root_ / "p" / "1.1"));
  EXPECT_FALSE(fs::exists(root_ / "p" / "1.2"));
  EXPECT_EQ(cache->stats().bytes, 800);
  EXPECT_EQ(cache->stats().evictions, 1);
}

TEST_F(SeriesCacheTest, RefusesSeriesOverBudgetAndKeepsPinned) {
  auto cache = Make(1000);
  std::atomic<int> calls{0};
  auto big = cache->Open("p", "1.9", Writer(11, 100, &calls));
  EXPECT_TRUE(absl::IsResourceExhausted(big.status())) << big.status();
  EXPECT_EQ(TempFolders(), 0);
  auto held = cache->Open("p", "1.1", Writer(6, 100, &calls));
  ASSERT_TRUE(held.ok());
  // 1.1 is pinned by `held`: a second 600-byte series cannot make room.
  auto other = cache->Open("p", "1.2", Writer(6, 100, &calls));
  EXPECT_TRUE(absl::IsResourceExhausted(other.status())) << other.status();
  held->reset();
  EXPECT_TRUE(cache->Open("p", "1.2", Writer(6, 100, &calls)).ok());
}

TEST_F(SeriesCacheTest, KeepsCompleteSeriesAcrossRestartsAndDropsTemporaries) {
  std::atomic<int> calls{0};
  {
    auto cache = Make(1 << 20);
    ASSERT_TRUE(cache->Open("p", "1.1", Writer(2, 10, &calls)).ok());
  }
  fs::create_directories(root_ / ".tmp-abcdef");
  auto cache = Make(1 << 20);
  EXPECT_EQ(TempFolders(), 0);
  auto again = cache->Open("p", "1.1", Writer(2, 10, &calls));
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE((*again)->hit);
  EXPECT_EQ(calls, 1);
}

TEST_F(SeriesCacheTest, RejectsPathsOutsideTheCache) {
  auto cache = Make(1 << 20);
  std::atomic<int> calls{0};
  EXPECT_TRUE(absl::IsInvalidArgument(cache->Open("..", "1.1", Writer(1, 1, &calls)).status()));
  EXPECT_TRUE(absl::IsInvalidArgument(cache->Open("p", "../1", Writer(1, 1, &calls)).status()));
  EXPECT_EQ(calls, 0);
}

TEST_F(SeriesCacheTest, CancelledWaiterStops) {
  auto cache = Make(1 << 20);
  std::atomic<int> calls{0};
  std::thread slow([&] { (void)cache->Open("p", "1.1", Writer(1, 1, &calls, 1500)); });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CancelToken::Source source;
  source.Cancel();
  const auto start = std::chrono::steady_clock::now();
  auto waited = cache->Open("p", "1.1", Writer(1, 1, &calls), source.token());
  EXPECT_TRUE(absl::IsCancelled(waited.status())) << waited.status();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(1000));
  slow.join();
}

}  // namespace
}  // namespace vpm::pacs

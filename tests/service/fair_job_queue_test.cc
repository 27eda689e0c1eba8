// FairJobQueue: lanes take turns, caps refuse with a message, gone jobs are
// purged (and handed back to drop) before anything is refused; WorkerPool
// shutdown drops what is still queued at its deadline.
#include "server/service/fair_job_queue.h"

#include <atomic>
#include <thread>

#include <gtest/gtest.h>

#include "server/service/worker_pool.h"
#include "tests/service/held_worker.h"

namespace vpm::service {
namespace {

Job Tagged(const std::string& lane, std::vector<std::string>* log, std::string tag,
           bool gone = false) {
  return Job{.lane = lane,
             .run = [log, tag] { log->push_back(tag); },
             .gone = [gone] { return gone; },
             .drop = [log, tag] { log->push_back("drop " + tag); }};
}

TEST(FairJobQueue, LanesTakeTurnsWhateverTheirBacklog) {
  FairJobQueue queue({});
  std::vector<std::string> log;
  std::vector<Job> dropped;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(queue.Push(Tagged("storm", &log, "s"), &dropped).ok());
  ASSERT_TRUE(queue.Push(Tagged("stream", &log, "i1"), &dropped).ok());
  ASSERT_TRUE(queue.Push(Tagged("stream", &log, "i2"), &dropped).ok());
  Job job;
  while (queue.Pop(&job)) job.run();
  EXPECT_EQ(log, (std::vector<std::string>{"s", "i1", "s", "i2", "s", "s", "s"}));
  EXPECT_EQ(queue.size(), 0);
  EXPECT_EQ(queue.lanes(), 0);
}

TEST(FairJobQueue, FullLaneIsRefusedButPurgesGoneJobsFirst) {
  FairJobQueue queue({.max_per_lane = 2, .max_total = 3});
  std::vector<std::string> log;
  std::vector<Job> dropped;
  ASSERT_TRUE(queue.Push(Tagged("a", &log, "a1", /*gone=*/true), &dropped).ok());
  ASSERT_TRUE(queue.Push(Tagged("a", &log, "a2"), &dropped).ok());
  // Full lane: a1 is gone, so it is purged and a3 fits.
  ASSERT_TRUE(queue.Push(Tagged("a", &log, "a3"), &dropped).ok());
  ASSERT_EQ(dropped.size(), 1u);
  dropped[0].drop();
  EXPECT_EQ(log, std::vector<std::string>{"drop a1"});
  dropped.clear();
  // Nothing gone now: refused, with the cap in the message.
  Status refused = queue.Push(Tagged("a", &log, "a4"), &dropped);
  EXPECT_TRUE(absl::IsResourceExhausted(refused));
  EXPECT_NE(refused.message().find("cap is 2"), std::string::npos) << refused;
  // The whole queue's cap.
  ASSERT_TRUE(queue.Push(Tagged("b", &log, "b1"), &dropped).ok());
  refused = queue.Push(Tagged("c", &log, "c1"), &dropped);
  EXPECT_TRUE(absl::IsResourceExhausted(refused));
  EXPECT_NE(refused.message().find("cap is 3"), std::string::npos) << refused;
  EXPECT_EQ(queue.size(), 3);
  EXPECT_EQ(queue.TakeAll().size(), 3u);
}

TEST(FairJobQueue, LaneAtItsRunningCapWaitsWhileOthersRun) {
  FairJobQueue queue({.max_running_per_lane = 1});
  std::vector<std::string> log;
  std::vector<Job> dropped;
  ASSERT_TRUE(queue.Push(Tagged("alice", &log, "a1"), &dropped).ok());
  ASSERT_TRUE(queue.Push(Tagged("alice", &log, "a2"), &dropped).ok());
  ASSERT_TRUE(queue.Push(Tagged("bob", &log, "b1"), &dropped).ok());
  // The server's own work (uncapped) in one lane is never held back.
  for (const char* tag : {"own1", "own2"}) {
    Job own = Tagged("own", &log, tag);
    own.capped = false;
    ASSERT_TRUE(queue.Push(std::move(own), &dropped).ok());
  }
  Job a1, b1, own1, own2, none;
  ASSERT_TRUE(queue.Pop(&a1));
  EXPECT_EQ(a1.lane, "alice");
  // Alice's lane is at its cap while a1 runs: bob's job comes next, then
  // both of the server's own.
  ASSERT_TRUE(queue.Pop(&b1));
  EXPECT_EQ(b1.lane, "bob");
  ASSERT_TRUE(queue.Pop(&own1));
  ASSERT_TRUE(queue.Pop(&own2));
  EXPECT_EQ(own2.lane, "own");
  EXPECT_EQ(queue.running("own"), 0);
  EXPECT_FALSE(queue.Pop(&none)) << "a2 ran beside a1";
  EXPECT_EQ(queue.running("alice"), 1);
  queue.Finished("alice", true);
  Job a2;
  ASSERT_TRUE(queue.Pop(&a2));
  a2.run();
  EXPECT_EQ(log, std::vector<std::string>{"a2"});
}

TEST(WorkerPool, ShutdownRunsTheQueueUntilItsDeadlineThenDropsTheRest) {
  auto pool = WorkerPool::Create({.threads = 1, .name = "test"});
  ASSERT_TRUE(pool.ok());
  std::atomic<int> ran{0}, dropped{0};
  std::atomic<bool> release{false};
  // A job that holds the only worker until released.
  ASSERT_TRUE((*pool)->Post([&] {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++ran;
  }));
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE((*pool)
                    ->Submit(Job{.lane = "x", .run = [&] { ++ran; }, .drop = [&] { ++dropped; }})
                    .ok());
  }
  std::thread releaser([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    release = true;
  });
  const auto start = std::chrono::steady_clock::now();
  const int64_t n = (*pool)->Shutdown(start + std::chrono::milliseconds(100));
  releaser.join();
  EXPECT_EQ(n, 10);
  EXPECT_EQ(dropped.load(), 10);
  EXPECT_EQ(ran.load(), 1);  // the running job finished; none of the queued ran
  // After shutdown, nothing is taken.
  EXPECT_TRUE(absl::IsUnavailable((*pool)->Submit(Job{.lane = "x", .run = [] {}})));
}

TEST(WorkerPool, ShutdownWithTimeLeftRunsEverythingQueued) {
  auto pool = WorkerPool::Create({.threads = 2, .name = "test"});
  ASSERT_TRUE(pool.ok());
  std::atomic<int> ran{0};
  for (int i = 0; i < 50; ++i) ASSERT_TRUE((*pool)->Post([&] { ++ran; }));
  EXPECT_EQ((*pool)->Shutdown(std::chrono::steady_clock::now() + std::chrono::seconds(10)), 0);
  EXPECT_EQ(ran.load(), 50);
}

// The server's own work on admitted calls (capped = false) is never refused:
// a refused still check or stream start would leave an admitted call
// without its answer. It still counts in the queue's size, so callers'
// requests meet the caps sooner.
TEST(FairJobQueue, OwnWorkIsNeverRefusedByTheCaps) {
  FairJobQueue queue({.max_per_lane = 2, .max_total = 3});
  std::vector<std::string> log;
  std::vector<Job> dropped;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(queue.Push(Job{.lane = "", .run = [] {}, .capped = false}, &dropped).ok());
  }
  EXPECT_EQ(queue.size(), 10);
  EXPECT_TRUE(absl::IsResourceExhausted(queue.Push(Tagged("user", &log, "u"), &dropped)));
  EXPECT_TRUE(dropped.empty());
}

// Delayed tasks and Post()s run however many callers' jobs fill the queue
// (lane "" was capped like a caller's lane, and due tasks beyond the cap
// were lost).
TEST(WorkerPool, DueTasksRunWhenTheQueueIsFull) {
  auto pool = WorkerPool::Create(
      {.threads = 1, .name = "test", .limits = {.max_per_lane = 4, .max_total = 8}});
  ASSERT_TRUE(pool.ok());
  std::atomic<int> ran{0};
  testing::HeldWorker worker(**pool);
  ASSERT_TRUE(worker.posted());
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE((*pool)->Submit(Job{.lane = "a", .run = [&] { ++ran; }}).ok());
    ASSERT_TRUE((*pool)->Submit(Job{.lane = "b", .run = [&] { ++ran; }}).ok());
  }
  EXPECT_TRUE(absl::IsResourceExhausted((*pool)->Submit(Job{.lane = "c", .run = [] {}})));
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE((*pool)->Post([&] { ++ran; }));
    ASSERT_TRUE((*pool)->PostAfter(std::chrono::milliseconds(1), [&] { ++ran; }));
  }
  // The delayed tasks fall due while the worker is held and the queue full.
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  worker.Release();
  // (Shutdown drops delayed tasks: wait for them to run first.)
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (ran < 8 + 20 + 20 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(ran.load(), 8 + 20 + 20);
  EXPECT_EQ((*pool)->queued(), 0);
}

// Every job submitted is run or dropped (its call answered), whatever falls
// due meanwhile: the churn soak's shutdown hang was gone callers' jobs that a
// due delayed task purged from a full queue and nobody dropped.
TEST(WorkerPool, EveryJobIsRunOrDroppedWhileDelayedTasksFallDue) {
  auto pool = WorkerPool::Create(
      {.threads = 1, .name = "test", .limits = {.max_per_lane = 2, .max_total = 4}});
  ASSERT_TRUE(pool.ok());
  std::atomic<int> ran{0}, dropped{0}, delayed_ran{0};
  testing::HeldWorker worker(**pool);
  ASSERT_TRUE(worker.posted());
  // Two callers' jobs whose callers are gone (cancelled while queued).
  for (const char* lane : {"a", "b"}) {
    ASSERT_TRUE((*pool)
                    ->Submit(Job{.lane = lane,
                                 .run = [&] { ++ran; },
                                 .gone = [] { return true; },
                                 .drop = [&] { ++dropped; }})
                    .ok());
  }
  for (int i = 0; i < 6; ++i) {
    ASSERT_TRUE((*pool)->PostAfter(std::chrono::milliseconds(1), [&] { ++delayed_ran; }));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  worker.Release();
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while ((delayed_ran < 6 || ran + dropped < 2) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(delayed_ran.load(), 6);
  EXPECT_EQ(ran + dropped, 2) << "a job neither run nor dropped: its call is never answered";
}

}  // namespace
}  // namespace vpm::service

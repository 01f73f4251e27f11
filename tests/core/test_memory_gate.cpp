#include "core/memory_gate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <unistd.h>

#include "core/memory.hpp"

namespace sandflow {
namespace {

constexpr std::int64_t kMB = 1'000'000;

// `n` jobs on `threads` threads through `gate`, each holding `peak` for a few milliseconds;
// returns the most that ran at once.
int most_at_once(MemoryGate& gate, int threads, int n, std::int64_t peak) {
  std::atomic<int> next{0}, running{0}, most{0};
  const auto worker = [&] {
    for (int i = next++; i < n; i = next++) {
      if (!gate.enter([] { return false; })) return;
      const int now = ++running;
      int seen = most.load();
      while (now > seen && !most.compare_exchange_weak(seen, now)) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      --running;
      gate.leave(peak);
    }
  };
  std::vector<std::thread> pool;
  for (int k = 0; k < threads; ++k) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  return most.load();
}

TEST(MemoryGate, JobsRunAsManyAtOnceAsTheirMeasuredPeakFits) {
  // 8 jobs asked for, 2 before one is measured, 1,000 MB for jobs of 300 MB: 3 at once
  MemoryGate gate(1000 * kMB, 8, 2);
  EXPECT_EQ(gate.allowed(), 8);  // nothing measured yet: what was asked
  EXPECT_LE(most_at_once(gate, 8, 40, 300 * kMB), 3);
  EXPECT_EQ(gate.allowed(), 3);
  EXPECT_EQ(gate.largest_peak(), 300 * kMB);
}

TEST(MemoryGate, BeforeAnyPeakIsKnownOnlyTheUnmeasuredCountRuns) {
  MemoryGate gate(1000 * kMB, 8, 2);
  std::atomic<int> inside{0};
  ASSERT_TRUE(gate.enter([] { return false; }));
  ASSERT_TRUE(gate.enter([] { return false; }));
  std::thread third([&] {
    if (gate.enter([] { return false; })) ++inside;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(inside.load(), 0);  // a third waits for the first peak
  gate.leave(10 * kMB);         // a small one: room for all eight
  third.join();
  EXPECT_EQ(inside.load(), 1);
  EXPECT_EQ(gate.allowed(), 8);
}

TEST(MemoryGate, AJobLargerThanTheBudgetStillRunsAlone) {
  MemoryGate gate(100 * kMB, 4, 1);
  EXPECT_EQ(most_at_once(gate, 4, 12, 500 * kMB), 1);  // (and every job ran: no deadlock)
  EXPECT_EQ(gate.allowed(), 1);
}

TEST(MemoryGate, WithoutABudgetOnlyTheJobsAskedForLimit) {
  MemoryGate gate(0, 3, 1);
  EXPECT_EQ(most_at_once(gate, 6, 60, 500 * kMB), 3);
  EXPECT_EQ(gate.allowed(), 3);
}

TEST(MemoryGate, AWaitingJobGivesUpWhenAStopIsAsked) {
  MemoryGate gate(100 * kMB, 2, 1);
  ASSERT_TRUE(gate.enter([] { return false; }));
  std::atomic<bool> stop{false}, entered{true};
  std::thread waiting([&] { entered = gate.enter([&] { return stop.load(); }); });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  stop = true;
  waiting.join();
  EXPECT_FALSE(entered.load());
}

TEST(AvailableMemory, IsWhatTheKernelSaysAndNoMore) {
  const std::int64_t free = available_memory_bytes();
  EXPECT_GT(free, 0);  // Linux has MemAvailable since 3.14
  // not more than the machine's memory (sysconf), nor less than a test's own few megabytes
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  EXPECT_LE(free, static_cast<std::int64_t>(pages) * page);
  EXPECT_GT(free, 16 * kMB);
}

}  // namespace
}  // namespace sandflow

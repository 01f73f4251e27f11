// CoreShareWatch (src/core/core_share.hpp): threads that outnumber the cores wait for them, and
// the watch says how much; a job that sleeps waits for nothing; and which OpenMP settings spin.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/core_share.hpp"

namespace sandflow {
namespace {

/// Sets an environment variable for the scope, restoring what was there.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      setenv(name, value, 1);
    else
      unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(CoreShare, ThreadsFourTimesAsManyAsTheCoresWaitThreeQuartersOfTheTime) {
  if (!threads_waiting_seconds()) GTEST_SKIP() << "this kernel keeps no schedstat counts";
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int n = 4 * cores;
  CoreShareWatch watch(n, 1.0);
  std::atomic<bool> stop{false};
  std::vector<std::thread> busy;
  for (int k = 0; k < n; ++k)
    busy.emplace_back([&] {
      volatile double x = 0;
      while (!stop.load(std::memory_order_relaxed)) x = x + 1;
    });
  std::optional<double> share;
  while (!(share = watch.poll())) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  stop = true;
  for (std::thread& t : busy) t.join();
  // n threads on `cores` cores: each has a core a quarter of the time, waits the rest (more when
  // other work shares the machine). Their time on a core would be a quarter.
  EXPECT_GE(*share, 0.5);
  EXPECT_LE(*share, 1.05);
}

TEST(CoreShare, AJobThatSleepsWaitsForNothing) {
  if (!threads_waiting_seconds()) GTEST_SKIP() << "this kernel keeps no schedstat counts";
  CoreShareWatch watch(2, 0.3);
  std::optional<double> share;
  while (!(share = watch.poll())) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_LT(*share, 0.1);
}

TEST(CoreShare, OpenMpThreadsSpinUnlessToldToWaitPassivelyOrBriefly) {
  {
    ScopedEnv policy("OMP_WAIT_POLICY", nullptr), count("GOMP_SPINCOUNT", nullptr);
    EXPECT_TRUE(openmp_threads_spin());
  }
  for (const char* passive : {"passive", "PASSIVE", " Passive"}) {
    ScopedEnv policy("OMP_WAIT_POLICY", passive), count("GOMP_SPINCOUNT", nullptr);
    EXPECT_FALSE(openmp_threads_spin()) << passive;
  }
  {
    ScopedEnv policy("OMP_WAIT_POLICY", "active"), count("GOMP_SPINCOUNT", nullptr);
    EXPECT_TRUE(openmp_threads_spin());
  }
  {
    ScopedEnv policy("OMP_WAIT_POLICY", nullptr), count("GOMP_SPINCOUNT", "1000");
    EXPECT_FALSE(openmp_threads_spin());
  }
}

}  // namespace
}  // namespace sandflow

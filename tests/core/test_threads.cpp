// The CPU lists that the thread checks read (core/threads.hpp): Linux's and libgomp's notation,
// and the CPUs this process may run on.
#include "core/threads.hpp"

#include <gtest/gtest.h>

#include <sched.h>

#include <algorithm>
#include <optional>
#include <vector>

#include "support/scratch.hpp"

namespace sandflow {
namespace {

TEST(CpuList, ReadsLinuxAndLibgompNotation) {
  EXPECT_EQ(cpu_list("0-1"), (std::vector<long>{0, 1}));
  EXPECT_EQ(cpu_list("0 3-5 8-14:3\n"), (std::vector<long>{0, 3, 4, 5, 8, 11, 14}));
  EXPECT_EQ(cpu_list("2,7"), (std::vector<long>{2, 7}));
  EXPECT_EQ(cpu_list(""), (std::vector<long>{}));
  for (const char* bad : {"x", "5-3", "1-4:0", "-1", "3-"})
    EXPECT_EQ(cpu_list(bad), std::nullopt) << bad;
}

// Every CPU the kernel lets this process run on is one the affinity check counts as usable: a
// cpuset read wrongly (a v1 path taken for v2's, a list misparsed) would warn of a CPU that works.
TEST(CpuList, TheCpusThisProcessRunsOnAreUsable) {
  cpu_set_t mask;
  CPU_ZERO(&mask);
  ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  const std::optional<std::vector<long>> usable = cpu_list(usable_cpus());
  ASSERT_TRUE(usable.has_value()) << usable_cpus();
  ASSERT_FALSE(usable->empty());
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (CPU_ISSET(cpu, &mask)) {
      EXPECT_NE(std::find(usable->begin(), usable->end(), cpu), usable->end())
          << "CPU " << cpu << " not in " << usable_cpus();
    }
  }
  if (const std::string cpuset = cgroup_cpus(); !cpuset.empty()) {
    const std::optional<std::vector<long>> online = cpu_list(online_cpus());
    ASSERT_TRUE(online.has_value());
    for (const long cpu : *usable)  // a cgroup's CPUs are online ones
      EXPECT_NE(std::find(online->begin(), online->end(), cpu), online->end()) << cpu;
  }
}

// A container's cpuset, read where each cgroup version keeps it: v2's one hierarchy, or v1's
// cpuset hierarchy among the others (a v1 path read as v2's finds nothing and would let libgomp
// stop the program unwarned).
TEST(CpuList, AContainersCpusetIsReadInEitherCgroupVersion) {
  const test::ScratchFolder box;
  const std::string root = box.dir().string() + "/fs";
  box.write("fs/job/cpuset.cpus.effective", "2-3\n");
  EXPECT_EQ(cgroup_cpus(box.write("v2", "0::/job\n"), root), "2-3");
  box.write("fs/cpuset/docker/abc/cpuset.effective_cpus", "5,7\n");
  const std::string v1 =
      "12:memory:/docker/abc\n4:cpu,cpuacct:/docker/abc\n"
      "3:cpuset:/docker/abc\n0::/\n";
  EXPECT_EQ(cgroup_cpus(box.write("v1", v1), root), "5,7");
  // no cpuset to read: nothing (the CPUs online stand)
  EXPECT_EQ(cgroup_cpus(box.write("none", "4:memory:/x\n0::/y\n"), root), "");
  EXPECT_EQ(cgroup_cpus(box.path("missing"), root), "");
}

}  // namespace
}  // namespace sandflow

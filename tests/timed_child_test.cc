// RunTimed (profiling/timed_child.h), which times and measures every command
// of the benchmarks against PMVS2: exit codes, signals, a command that
// cannot start, the environment, and the peak split into files and
// anonymous memory.
#include "timed_child.h"

#include <gtest/gtest.h>

#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

TEST(TimedChildTest, SplitsThePeakIntoFilesAndAnonymousMemory) {
  // 96 MiB written and held for 400 ms: 40 samples or so.
  const ChildUsage u = RunTimed({{SAPMVS_HOLD_MEMORY_PATH, "96", "400"}, {}, {}});
  ASSERT_TRUE(u.Ok()) << u.Describe();
  EXPECT_GE(u.wall_seconds, 0.4);
  EXPECT_GE(u.peak_rss_mib, 96);
  EXPECT_GE(u.anonymous_at_peak_mib, 96);
  // The parts of a sample, which is at most the peak.
  EXPECT_LE(u.anonymous_at_peak_mib + u.files_at_peak_mib, u.peak_rss_mib + 1);
  // Its files are the program and the C and C++ libraries: some, and far
  // less than what it allocated.
  EXPECT_GT(u.files_at_peak_mib, 0);
  EXPECT_LT(u.files_at_peak_mib, 32);
}

TEST(TimedChildTest, ReportsTheExitCodeAndTheSignal) {
  const ChildUsage exited = RunTimed({{"/bin/sh", "-c", "exit 3"}, {}, {}});
  EXPECT_FALSE(exited.Ok());
  EXPECT_EQ(exited.exit_code, 3);
  EXPECT_EQ(exited.Describe(), "exit 3");
  const ChildUsage killed = RunTimed({{"/bin/sh", "-c", "kill -9 $$"}, {}, {}});
  EXPECT_FALSE(killed.Ok());
  EXPECT_EQ(killed.signal, 9);
  EXPECT_EQ(killed.Describe().rfind("signal 9 (", 0), 0u) << killed.Describe();
}

TEST(TimedChildTest, SetsTheEnvironmentInTheChildOnly) {
  const ChildUsage u = RunTimed({{"/bin/sh", "-c", "test \"$SAPMVS_TIMED_CHILD\" = yes"},
                                 {{"SAPMVS_TIMED_CHILD", "yes"}},
                                 {}});
  EXPECT_TRUE(u.Ok()) << u.Describe();
  EXPECT_EQ(std::getenv("SAPMVS_TIMED_CHILD"), nullptr);
}

TEST(TimedChildTest, ACommandThatCannotStartThrows) {
  try {
    RunTimed({{"/nonexistent/sapmvs-timed-child"}, {}, {}});
    FAIL() << "no Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/sapmvs-timed-child: cannot run"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

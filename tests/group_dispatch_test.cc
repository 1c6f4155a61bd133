// The pieces of `run` under mpirun that need no MPI: group claims
// (group_dispatch.h), the per-rank --device entry (device_spec.h), the
// launcher's environment and the threads of a rank (mpi_session.h).
#include "run/group_dispatch.h"

#include <gtest/gtest.h>
#include <sched.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "match/device_spec.h"
#include "run/mpi_session.h"
#include "sapmvs/run/run_options.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

TEST(GroupClaim, OnlyTheFirstCreateWins) {
  const fs::path dir = test::ScratchDir();
  const fs::path claim = ClaimPath(dir, 2);
  EXPECT_EQ(claim.filename(), "group_003.claim");
  EXPECT_TRUE(CreateClaim(claim, "run a rank 0 pid 1\n"));
  EXPECT_FALSE(CreateClaim(claim, "run a rank 1 pid 2\n"));
  EXPECT_EQ(test::Slurp(claim), "run a rank 0 pid 1\n");
}

TEST(GroupClaim, AMissingFolderIsAnError) {
  EXPECT_THROW(CreateClaim(test::ScratchDir() / "missing" / "group_001.claim", "x"), Error);
}

TEST(GroupClaim, RemoveClaimsLeavesOtherFiles) {
  const fs::path dir = test::ScratchDir();
  for (const char* f : {"group_001.claim", "group_012.claim", "group_001.ply", "group_001.json",
                        "plan.json", "group_x.claim", "notes.claim"}) {
    std::ofstream(dir / f) << "x";
  }
  RemoveClaims(dir);
  EXPECT_FALSE(fs::exists(dir / "group_001.claim"));
  EXPECT_FALSE(fs::exists(dir / "group_012.claim"));
  for (const char* f :
       {"group_001.ply", "group_001.json", "plan.json", "group_x.claim", "notes.claim"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
  }
}

TEST(DeviceForLocalRank, TakesEntryRankModN) {
  EXPECT_EQ(DeviceForLocalRank("0,1", 0), "0");
  EXPECT_EQ(DeviceForLocalRank("0,1", 1), "1");
  EXPECT_EQ(DeviceForLocalRank("0, 1", 3), "1");
  EXPECT_EQ(DeviceForLocalRank("nvidia,pocl,reference", 2), "reference");
  // One device for every rank, as before.
  EXPECT_EQ(DeviceForLocalRank("pocl", 5), "pocl");
  EXPECT_EQ(DeviceForLocalRank("", 1), "") << "no SAPMVS_DEVICE in the test's environment";
}

TEST(DeviceForLocalRank, RunOptionsRefuseEmptyEntries) {
  RunOptions o;
  o.block = "b.yaml";
  o.out = "out";
  o.device = "0,1";
  EXPECT_EQ(o.Problem(), "");
  for (const char* bad : {"0,,1", "0,", ",1", " , "}) {
    o.device = bad;
    EXPECT_NE(o.Problem().find("--device as a comma list"), std::string::npos) << bad;
  }
}

// Sets the launcher's variables for one test, and removes them after.
class LauncherEnvTest : public ::testing::Test {
 protected:
  void TearDown() override {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK",
                          "OMPI_COMM_WORLD_LOCAL_SIZE", "PMI_SIZE", "PMI_RANK"}) {
      ::unsetenv(v);
    }
  }
};

TEST_F(LauncherEnvTest, NoLauncherNoRanks) {
  EXPECT_EQ(ReadLauncherEnvironment().ranks, 0);
  EXPECT_EQ(RankThreadCount(), 0);
}

TEST_F(LauncherEnvTest, ReadsOpenMpiAndPmi) {
  ::setenv("OMPI_COMM_WORLD_SIZE", "4", 1);
  ::setenv("OMPI_COMM_WORLD_RANK", "3", 1);
  ::setenv("OMPI_COMM_WORLD_LOCAL_SIZE", "2", 1);
  LauncherEnvironment env = ReadLauncherEnvironment();
  EXPECT_EQ(env.ranks, 4);
  EXPECT_EQ(env.rank, 3);
  EXPECT_EQ(env.local_ranks, 2);
  TearDown();
  ::setenv("PMI_SIZE", "2", 1);
  ::setenv("PMI_RANK", "1", 1);
  env = ReadLauncherEnvironment();
  EXPECT_EQ(env.ranks, 2);
  EXPECT_EQ(env.rank, 1);
  EXPECT_EQ(env.local_ranks, 0);
  ::setenv("PMI_SIZE", "two", 1);
  EXPECT_EQ(ReadLauncherEnvironment().ranks, 0);
}

TEST_F(LauncherEnvTest, RanksOfOneMachineShareItsCores) {
  ::setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
  ::setenv("OMPI_COMM_WORLD_LOCAL_SIZE", "1", 1);
  EXPECT_EQ(RankThreadCount(), 0) << "alone on its machine: all cores";
  const long cores = ::sysconf(_SC_NPROCESSORS_ONLN);
  cpu_set_t set;
  ASSERT_EQ(::sched_getaffinity(0, sizeof(set), &set), 0);
  if (CPU_COUNT(&set) < cores) {
    GTEST_SKIP() << "this process is bound to " << CPU_COUNT(&set) << " of " << cores
                 << " cores: a rank takes those, whatever the count of ranks";
  }
  ::setenv("OMPI_COMM_WORLD_LOCAL_SIZE", "2", 1);
  EXPECT_EQ(RankThreadCount(), std::max(1L, cores / 2));
  ::setenv("OMPI_COMM_WORLD_LOCAL_SIZE", std::to_string(4 * cores).c_str(), 1);
  EXPECT_EQ(RankThreadCount(), 1) << "more ranks than cores: one thread each";
}

}  // namespace
}  // namespace sapmvs

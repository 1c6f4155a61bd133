// `mpirun -np 2 sapmvs run`: the groups shared among two ranks give the
// cloud of one process byte for byte, a rerun takes over the claims of a
// killed run, and each rank takes its own --device entry. Skipped when
// sapmvs was built without MPI or mpirun is missing; then the refusal of a
// launch of several ranks is checked instead.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::RunCli;

#ifdef SAPMVS_MPIEXEC
constexpr const char* kMpiexec = SAPMVS_MPIEXEC;
#else
constexpr const char* kMpiexec = "";
#endif

// Two groups of two images on `tiny` (it is one group by default), both
// matchable with two views.
constexpr const char* kTwoGroups = "--max-images 2 --min-image-num 2";

class CliMpiTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SAPMVS_REQUIRE_OPENCL_DEVICE();
#ifndef SAPMVS_HAVE_MPI
    GTEST_SKIP() << "sapmvs was built without MPI (libopenmpi-dev not found by CMake)";
#endif
    if (std::string(kMpiexec).empty() || ::access(kMpiexec, X_OK) != 0) {
      GTEST_SKIP() << "no mpirun (openmpi-bin) found by CMake";
    }
    dir_ = test::ScratchDir();
  }

  static fs::path Block() { return test::Simulated("tiny", 1) / "block.yaml"; }

  // `sapmvs ARGS` under mpirun with `ranks` processes; CI runs as root,
  // which OpenMPI refuses unless told.
  static test::CliResult RunRanks(int ranks, const std::string& args) {
    return RunCli(args, std::string("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ") +
                            kMpiexec + " --oversubscribe -np " + std::to_string(ranks));
  }

  fs::path dir_;
};

TEST_F(CliMpiTest, TwoRanksWriteTheCloudOfOneProcess) {
  const fs::path one = dir_ / "one", two = dir_ / "two";
  const auto r1 =
      RunCli("-q run " + Block().string() + " --out " + one.string() + " " + kTwoGroups);
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  const auto r2 =
      RunRanks(2, "-q run " + Block().string() + " --out " + two.string() + " " + kTwoGroups);
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(test::Slurp(one / "cloud.ply"), test::Slurp(two / "cloud.ply"));
  for (const char* f :
       {"cloud.las", "dsm.tif", "dsm.png", "ortho.tif", "report.json", "report.html"}) {
    EXPECT_TRUE(fs::exists(two / f)) << f;
  }
  // Rank 0 alone prints the summary; the claims and the images the ranks
  // kept at the level are gone.
  size_t wrote = 0;
  for (size_t at = 0; (at = r2.out.find("wrote ", at)) != std::string::npos; ++at) ++wrote;
  EXPECT_EQ(wrote, 11u) << r2.out;
  for (const auto& e : fs::directory_iterator(two / "groups")) {
    EXPECT_NE(e.path().extension(), ".claim") << e.path();
  }
  EXPECT_FALSE(fs::exists(two / "groups" / "levels"));
  const nlohmann::json report = nlohmann::json::parse(test::Slurp(two / "report.json"));
  EXPECT_EQ(report.value("mpi_ranks", 0), 2);
  ASSERT_EQ(report["groups"].size(), 2u);
  for (const auto& g : report["groups"]) {
    EXPECT_TRUE(g.contains("rank")) << g.dump();
    EXPECT_GT(g.value("points", 0L), 0) << g.dump();
  }
}

// A killed run leaves claims naming its run id and groups without a done
// checkpoint: the same command again matches them and merges.
TEST_F(CliMpiTest, RerunTakesOverTheClaimsOfAKilledRun) {
  const fs::path one = dir_ / "one", out = dir_ / "out";
  const auto r1 =
      RunCli("-q run " + Block().string() + " --out " + one.string() + " " + kTwoGroups);
  ASSERT_EQ(r1.exit_code, 0) << r1.err;
  const auto first = RunCli("-q run " + Block().string() + " --out " + out.string() + " " +
                            kTwoGroups + " --max-groups 1");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_FALSE(fs::exists(out / "cloud.ply"));
  std::ofstream(out / "groups" / "group_001.claim") << "run killed-run rank 0 pid 1\n";
  std::ofstream(out / "groups" / "group_002.claim") << "run killed-run rank 1 pid 2\n";
  const auto again =
      RunRanks(2, "-q run " + Block().string() + " --out " + out.string() + " " + kTwoGroups);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(test::Slurp(one / "cloud.ply"), test::Slurp(out / "cloud.ply"));
  EXPECT_FALSE(fs::exists(out / "groups" / "group_002.claim"));
}

// --device 0,bogus: local rank 1 takes "bogus" and stops the job, naming its
// rank, before any output is written.
TEST_F(CliMpiTest, EachRankTakesItsDeviceEntry) {
  const fs::path out = dir_ / "out";
  const auto r = RunRanks(2, "-q run " + Block().string() + " --out " + out.string() + " " +
                                 kTwoGroups + " --device 0,no-such-device");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("sapmvs: rank 1 of 2: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no-such-device"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "cloud.ply"));
}

// Built without MPI, a launch of several ranks would be N one-process runs
// writing one folder: refused before any work.
TEST(CliMpiRefusal, BuiltWithoutMpiRefusesSeveralRanks) {
#ifdef SAPMVS_HAVE_MPI
  GTEST_SKIP() << "sapmvs was built with MPI";
#endif
  // Refused before the block is read: it need not exist.
  const fs::path out = test::ScratchDir() / "out";
  const auto r =
      RunCli("-q run " + (test::ScratchDir() / "no_block.yaml").string() + " --out " + out.string(),
             "OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=0");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err,
            "sapmvs: this sapmvs was built without MPI; install openmpi-bin libopenmpi-dev and "
            "rebuild (scripts/install-deps.sh)\n");
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace sapmvs

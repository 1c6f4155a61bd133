#include "sapmvs/util/output_folder.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "file_size_limit.h"
#include "run/run_checkpoint.h"
#include "run/run_report.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

using test::Slurp;

void Spit(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

std::string ErrorOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

using OutputFolderTest = test::ScratchTest;

TEST_F(OutputFolderTest, NewFolderIsCreatedWithAMarkerHoldingThePid) {
  const fs::path out = dir_ / "run";
  {
    const OutputFolder folder(out, "run");
    EXPECT_EQ(Slurp(out / ".sapmvs_run"), "sapmvs run pid " + std::to_string(::getpid()) + "\n");
  }
  EXPECT_TRUE(fs::exists(out / ".sapmvs_run"));  // the marker outlives the lock
  EXPECT_NO_THROW(OutputFolder(out, "run"));
}

TEST_F(OutputFolderTest, EmptyFolderIsTaken) {
  EXPECT_NO_THROW(OutputFolder(dir_, "simulate"));
  EXPECT_TRUE(fs::exists(dir_ / ".sapmvs_simulate"));
}

TEST_F(OutputFolderTest, ForeignFolderIsRefusedAndLeftAlone) {
  Spit(dir_ / "block.yaml", "mine");
  EXPECT_EQ(ErrorOf([&] { OutputFolder f(dir_, "simulate"); }),
            dir_.string() +
                ": folder is not empty and was not written by sapmvs simulate (no "
                ".sapmvs_simulate); give a new or empty folder");
  EXPECT_EQ(Slurp(dir_ / "block.yaml"), "mine");
  EXPECT_FALSE(fs::exists(dir_ / ".sapmvs_simulate"));
  // Another command's folder is not this one's either.
  const fs::path run = dir_ / "run";
  { const OutputFolder f(run, "run"); }
  EXPECT_THROW(OutputFolder::Check(run, "simulate"), Error);
}

TEST_F(OutputFolderTest, RunFolderOfAnEarlierVersionIsAccepted) {
  Spit(dir_ / "groups" / "plan.json", "{}");
  Spit(dir_ / "cloud.ply", "ply");
  EXPECT_NO_THROW(OutputFolder(dir_, "run"));
  EXPECT_THROW(OutputFolder::Check(dir_, "simulate"), Error);
}

TEST_F(OutputFolderTest, SecondClaimIsRefusedNamingTheHoldersPid) {
  const OutputFolder first(dir_, "run");
  const std::string expected = dir_.string() + ": in use by another sapmvs run (pid " +
                               std::to_string(::getpid()) +
                               "); wait for it to finish or give another --out";
  EXPECT_EQ(ErrorOf([&] { OutputFolder::Check(dir_, "run"); }), expected);
  EXPECT_EQ(ErrorOf([&] { OutputFolder second(dir_, "run"); }), expected);
}

// flock goes with the process: a marker left by a killed run, naming its
// pid, does not block the next one.
TEST_F(OutputFolderTest, MarkerOfAKilledRunDoesNotBlock) {
  Spit(dir_ / ".sapmvs_run", "sapmvs run pid 999999\n");
  const OutputFolder folder(dir_, "run");
  EXPECT_EQ(Slurp(dir_ / ".sapmvs_run"), "sapmvs run pid " + std::to_string(::getpid()) + "\n");
}

TEST_F(OutputFolderTest, RestartRemovesOnlyWhatRunWrote) {
  const std::vector<std::string> ours = {"cloud.ply",
                                         "cloud.las",
                                         "dsm.tif",
                                         "dsm.tif.aux.xml",
                                         "dsm.png",
                                         "report.json",
                                         "profile.csv",
                                         "profile.json",
                                         "groups/plan.json",
                                         "groups/group_001.ply",
                                         "groups/group_001.json",
                                         "groups/group_1234.ply"};
  const std::vector<std::string> theirs = {"notes.txt",          "cloud.ply.bak",
                                           "groups/notes.txt",   "groups/group_001.txt",
                                           "groups/group_x.ply", "groups/old/group_001.ply"};
  for (const auto& f : ours) Spit(dir_ / f, "x");
  for (const auto& f : theirs) Spit(dir_ / f, "x");
  RemoveRunOutputs(dir_);
  for (const auto& f : ours) EXPECT_FALSE(fs::exists(dir_ / f)) << f;
  for (const auto& f : theirs) EXPECT_TRUE(fs::exists(dir_ / f)) << f;
}

// report.json, plan.json and the groups' status files go through one writer.
TEST_F(OutputFolderTest, FullDiskAtAJsonFileFailsNamingItAndKeepsTheOldOne) {
  const fs::path path = dir_ / "report.json";
  Spit(path, "{\"old\": true}\n");
  nlohmann::json j;
  for (int i = 0; i < 200; ++i) j["key_" + std::to_string(i)] = i;
  std::string what;
  {
    test::FileSizeLimit limit(512);
    if (!limit.ok()) GTEST_SKIP() << "cannot set RLIMIT_FSIZE";
    what = ErrorOf([&] { WriteJsonFile(path, j); });
  }
  EXPECT_EQ(what, path.string() + ": write failed: File too large");
  EXPECT_EQ(Slurp(path), "{\"old\": true}\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

// A group status an earlier version committed empty on a full disk: that
// group is matched again instead of every resume failing until --restart.
TEST_F(OutputFolderTest, EmptyGroupStatusMarksTheGroupUnfinished) {
  const RunCheckpoints checkpoints(dir_, Block(), GroupingPlan(), MatcherOptions(), false);
  Spit(checkpoints.CloudPath(0), "ply");
  Spit(checkpoints.StatusPath(0), "");
  EXPECT_FALSE(checkpoints.Done(0));
  Spit(checkpoints.StatusPath(0), "{\"status\": \"done\"}");
  EXPECT_TRUE(checkpoints.Done(0));
}

}  // namespace
}  // namespace sapmvs

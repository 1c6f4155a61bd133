#include "run/run_report.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "test_util.h"

namespace sapmvs {
namespace {

// report.json of a made-up run, without matching anything: the fields that
// depend on the block and on --profile.
class RunReportTest : public test::ScratchTest {
 protected:
  nlohmann::json Write(const std::string& crs, bool profile) {
    RunOptions options;
    options.block = "block.yaml";
    options.out = dir_;
    options.profile = profile;
    options.command_line = {"sapmvs", "run", "block.yaml", "--out", dir_.string()};
    RunReport report;
    report.start_time = std::chrono::system_clock::time_point(std::chrono::seconds(1700000000));
    report.end_time = report.start_time + std::chrono::milliseconds(2500);
    report.bounds_min = {1, 2, 3};
    report.bounds_max = {4, 5, 6};
    StageTime stage;
    stage.wall = 2;
    stage.device = profile ? 1.5 : 0;
    report.stats.stages.emplace_back("seeds", stage);
    KernelTime kernel;
    kernel.launches = 3;
    kernel.seconds = profile ? 1.5 : 0;
    report.stats.kernels["patch_refine"] = kernel;
    Block block;
    block.crs = crs;
    WriteRunReport(options, report, block, GroupingPlan{});
    std::ifstream in(dir_ / "report.json");
    return nlohmann::json::parse(in);
  }
};

TEST_F(RunReportTest, ProvenanceTimesAndBounds) {
  const nlohmann::json j = Write("EPSG:32632", false);
  EXPECT_EQ(j.at("report_version"), kRunReportVersion);
  EXPECT_EQ(j.at("command_line").size(), 5u);
  EXPECT_EQ(j.at("start_time"), "2023-11-14T22:13:20.000Z");
  EXPECT_EQ(j.at("end_time"), "2023-11-14T22:13:22.500Z");
  EXPECT_EQ(j.at("bounds").at("min").at("y"), 2.0);
  EXPECT_EQ(j.at("bounds").at("max").at("z"), 6.0);
  EXPECT_EQ(j.at("crs").at("epsg"), 32632);
  EXPECT_EQ(j.at("crs").at("definition"), "EPSG:32632");
}

TEST_F(RunReportTest, NoCrsIsNull) { EXPECT_TRUE(Write("", false).at("crs").is_null()); }

TEST_F(RunReportTest, DeviceTimesOnlyWhenProfiled) {
  for (const bool profile : {false, true}) {
    SCOPED_TRACE(profile ? "--profile" : "no --profile");
    const nlohmann::json j = Write("", profile);
    ASSERT_FALSE(j.at("stages").empty());
    EXPECT_EQ(j.at("stages").at(0).at("stage"), "seeds");
    EXPECT_EQ(j.at("stages").at(0).contains("device_seconds"), profile);
    EXPECT_EQ(j.at("kernels").at(0).contains("device_seconds"), profile);
    EXPECT_EQ(j.at("kernels").at(0).at("launches"), 3);
    if (profile) {
      EXPECT_EQ(j.at("kernels").at(0).at("device_seconds"), 1.5);
    }
  }
}

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cl_runtime.h"
#include "cli_test_util.h"
#include "sapmvs/error.h"
#include "sapmvs/ply_io.h"
#include "sapmvs/simulate.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::RunCli;

bool HaveOpenClDevice() {
  try {
    return !ListDevices().empty();
  } catch (const Error&) {
    return false;
  }
}

class CliRunTest : public ::testing::Test {
 protected:
  // One simulated tiny block for the suite, in a folder unique to the process.
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("sapmvs_cli_run_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    SimulateOptions o;
    o.preset = "tiny";
    o.out = *root_ / "tiny";
    o.seed = 1;
    o.quiet = true;
    Simulate(o);
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*root_, ec);
    delete root_;
    root_ = nullptr;
  }

  void SetUp() override {
    out_ = *root_ / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(out_);
  }

  static fs::path Block() { return *root_ / "tiny" / "block.yaml"; }
  // Nothing at all under the output folder (or no folder).
  bool NoOutput() const { return !fs::exists(out_) || fs::is_empty(out_); }

  static fs::path* root_;
  fs::path out_;
};

fs::path* CliRunTest::root_ = nullptr;

TEST_F(CliRunTest, WritesCloudAndReport) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const auto r = RunCli("run " + Block().string() + " --out " + out_.string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("cloud.ply"), std::string::npos) << r.out;

  const PointCloud cloud = ReadPly(out_ / "cloud.ply");
  ASSERT_GT(cloud.points.size(), 0u);
  EXPECT_TRUE(cloud.has_normals);
  EXPECT_TRUE(cloud.has_colors);
  EXPECT_TRUE(cloud.has_scores);
  EXPECT_TRUE(cloud.has_views);
  EXPECT_FALSE(cloud.crs.empty());
  EXPECT_NE(cloud.crs.find("32632"), std::string::npos) << cloud.crs;  // the tiny block's CRS
  // Default min_image_num is 3.
  for (const CloudPoint& p : cloud.points) ASSERT_GE(p.num_views, 3);

  std::ifstream in(out_ / "report.json");
  ASSERT_TRUE(in) << "no report.json";
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("points").get<long>(), static_cast<long>(cloud.points.size()));
  EXPECT_EQ(j.at("mode"), "sapmvs");
  EXPECT_EQ(j.at("level"), 1);
  EXPECT_EQ(j.at("images"), 4);
  ASSERT_TRUE(j.at("stages").is_array());
  ASSERT_FALSE(j.at("stages").empty());
  for (const auto& stage : j.at("stages")) {
    EXPECT_TRUE(stage.at("stage").is_string()) << stage;
    ASSERT_TRUE(stage.at("wall_seconds").is_number()) << stage;
    EXPECT_GE(stage.at("wall_seconds").get<double>(), 0.0) << stage;
  }
  ASSERT_TRUE(j.at("kernels").is_array());
  ASSERT_FALSE(j.at("kernels").empty());
  bool launched = false;
  for (const auto& kernel : j.at("kernels")) {
    EXPECT_TRUE(kernel.at("kernel").is_string()) << kernel;
    launched = launched || kernel.at("launches").get<long>() > 0;
  }
  EXPECT_TRUE(launched) << j.at("kernels");

  // Nothing but the two outputs: no temporary file left behind.
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(out_)) files += e.is_regular_file();
  EXPECT_EQ(files, 2);
}

TEST_F(CliRunTest, MinImageNumTwoIsAccepted) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const auto r =
      RunCli("run " + Block().string() + " --out " + out_.string() + " --min-image-num 2 -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud cloud = ReadPly(out_ / "cloud.ply");
  ASSERT_GT(cloud.points.size(), 0u);
  // The option reached the matcher: with 4 images in 2 strips, many points
  // are seen in 2 images only, and none in fewer.
  long two = 0;
  for (const CloudPoint& p : cloud.points) {
    ASSERT_GE(p.num_views, 2);
    two += p.num_views == 2;
  }
  EXPECT_GT(two, 0);
  std::ifstream in(out_ / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("points").get<long>(), static_cast<long>(cloud.points.size()));
}

TEST_F(CliRunTest, MissingBlockIsOneLineNamingThePath) {
  const fs::path missing = *root_ / "no_such_block" / "block.yaml";
  const auto r = RunCli("run " + missing.string() + " --out " + out_.string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;
  EXPECT_TRUE(NoOutput());
}

TEST_F(CliRunTest, UnknownModeIsOneLineNamingIt) {
  const auto r = RunCli("run " + Block().string() + " --out " + out_.string() + " --mode foo");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("'foo'"), std::string::npos) << r.err;
  EXPECT_TRUE(NoOutput());
}

TEST_F(CliRunTest, NegativeLevelIsOneLineNamingIt) {
  const auto r = RunCli("run " + Block().string() + " --out " + out_.string() + " --level -1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("level"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-1"), std::string::npos) << r.err;
  EXPECT_TRUE(NoOutput());
}

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "cli_test_util.h"
#include "sapmvs/simulate/simulate.h"
#include "simulate/sim_presets.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::RunCli;

class CliPlanTest : public ::testing::Test {
 protected:
  // The campus preset's cameras as a native block with blank images of the
  // right size: `plan` reads the headers only, and rendering 67 images would
  // take minutes.
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("sapmvs_cli_plan_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    fs::create_directories(*root_ / "campus" / "images");
    const sim::Preset p = sim::FindPreset("campus");
    const sim::FlightPlan plan = sim::PlanFlight(p, p.camera, false, p.flight.exposure, 1);
    const Eigen::Vector3d offset = sim::WorldOffset(plan.scene_width, plan.scene_height);
    std::ofstream ori(*root_ / "campus" / "orientation.txt");
    ori << std::fixed << std::setprecision(6);
    const cv::Mat blank(p.camera.height, p.camera.width, CV_8UC1, cv::Scalar(0));
    for (const PlannedImage& im : plan.images) {
      const Eigen::Vector3d c = im.center + offset;
      ori << im.name << " " << c.x() << " " << c.y() << " " << c.z() << " " << im.omega << " "
          << im.phi << " " << im.kappa << "\n";
      cv::imwrite((*root_ / "campus" / "images" / (im.name + ".png")).string(), blank);
    }
    std::ofstream(*root_ / "campus" / "block.yaml")
        << "ground_height: " << offset.z()
        << "\ncamera:\n  name: campus\n  width: " << p.camera.width
        << "\n  height: " << p.camera.height << "\n  focal_mm: " << p.camera.focal_mm
        << "\n  pixel_um: " << std::setprecision(9) << p.camera.pixel_um
        << "\nimages: images\norientation:\n  file: orientation.txt\n  type: angles\n"
           "  angles: omega-phi-kappa\n  units: deg\n";
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*root_, ec);
    delete root_;
    root_ = nullptr;
  }
  static std::string Block() { return (*root_ / "campus" / "block.yaml").string(); }

  static fs::path* root_;
};
fs::path* CliPlanTest::root_ = nullptr;

TEST_F(CliPlanTest, PrintsTheGroupsOfTable3) {
  const auto r = RunCli("plan " + Block() + " --strategy strip --max-images 6");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("strips      4: 16 17 18 16 images"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("groups      12\n"), std::string::npos) << r.out;
  // group, strip, image numbers, names, count
  EXPECT_TRUE(
      std::regex_search(r.out, std::regex(R"(\n +1 +1 +1 2 3 4 5 6 +IMG_0001~IMG_0006 +6 )")))
      << r.out;
  EXPECT_TRUE(
      std::regex_search(r.out, std::regex(R"(\n +12 +4 +64 65 66 67 +IMG_0064~IMG_0067 +4 )")))
      << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '~'), 12) << r.out;
  EXPECT_NE(r.out.find("memory budget 8 GiB"), std::string::npos) << r.out;
}

TEST_F(CliPlanTest, JsonIsWrittenAndValid) {
  const fs::path json = *root_ / "plan.json";
  const auto r =
      RunCli("plan " + Block() + " --strategy strip --json " + json.string() + " --max-images 5");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["strategy"], "strip");
  EXPECT_EQ(j["options"]["max_images"], 5);
  ASSERT_EQ(j["strips"].size(), 4u);
  // 16 -> 4+4+4+4 (5+5+5+1 would leave a group under 4), 17 -> 5+4+4+4,
  // 18 -> 5+5+4+4, 16.
  ASSERT_EQ(j["groups"].size(), 16u);
  EXPECT_EQ(j["groups"][0]["indices"], nlohmann::json({0, 1, 2, 3}));
  EXPECT_TRUE(j["outliers"].is_array());
  EXPECT_EQ(j["groups"][0]["names"][0], "IMG_0001");
  EXPECT_EQ(j["groups"][0]["strip"], 0);
  EXPECT_GT(j["groups"][0]["memory"]["device_bytes"].get<double>(), 0);
  EXPECT_EQ(j["groups"][0]["center"].size(), 2u);
  for (const auto& e : fs::directory_iterator(*root_))
    EXPECT_EQ(e.path().filename().string().find(".plan.json.tmp"), std::string::npos);
}

TEST_F(CliPlanTest, FootprintStrategy) {
  const auto r = RunCli("plan " + Block() + " --strategy footprint --max-images 6");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("strategy    footprint"), std::string::npos) << r.out;
}

TEST_F(CliPlanTest, BadStrategyIsOneLine) {
  const auto r = RunCli("plan " + Block() + " --strategy strips");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("'strips'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("strip or footprint"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(CliPlanTest, BadMemoryBudgetIsOneLine) {
  for (const char* bad : {"8Q", "lots", "-1G"}) {
    const auto r = RunCli("plan " + Block() + " --memory-budget=" + bad);
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(std::string("--memory-budget: bad memory size '") + bad + "'"),
              std::string::npos)
        << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

TEST_F(CliPlanTest, BudgetTooSmallIsOneLine) {
  const auto r = RunCli("plan " + Block() + " --memory-budget 1M");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("memory budget 1 MiB is too small"), std::string::npos) << r.err;
}

TEST_F(CliPlanTest, JsonInAMissingFolderFailsBeforeAnyOutput) {
  const auto r = RunCli("plan " + Block() + " --json /nonexistent/dir/plan.json");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/nonexistent/dir"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test_util.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::RunCli;

constexpr double kX0 = 512000, kY0 = 5405000, kZ = 300;

// The lines of `text` that start with `prefix`.
std::vector<std::string> LinesStartingWith(const std::string& text, const std::string& prefix) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) out.push_back(line);
  }
  return out;
}

class CliEvaluateTest : public test::ScratchTest {
 protected:
  // Cloud point k sits at (kX0 + Dx(k), kY0 + Dy(k)), never on a 0.5 cell edge.
  static double Dx(double k) { return 2.05 + 0.2 * k; }
  static double Dy(double k) { return 5.03 + 0.1 * k; }

  // Flat LiDAR at kZ on a 0.5 grid over 20 x 20, and a cloud over its middle
  // with 60 points at dz = 0.1, 6 at dz = 1.5 and 3 at dz = -8; 2 more lie
  // outside the LiDAR.
  void SetUp() override {
    ScratchTest::SetUp();
    std::vector<PointRecord> lidar;
    for (int j = 0; j <= 40; ++j) {
      for (int i = 0; i <= 40; ++i) {
        PointRecord p;
        p.x = kX0 + 0.5 * i;
        p.y = kY0 + 0.5 * j;
        p.z = kZ;
        lidar.push_back(p);
      }
    }
    WriteLas(dir_ / "lidar.las", lidar, {"EPSG:32632"});
    PointCloud cloud;
    auto add = [&](int n, double dz) {
      for (int i = 0; i < n; ++i) {
        CloudPoint p;
        const double k = static_cast<double>(cloud.points.size());
        p.position = {kX0 + Dx(k), kY0 + Dy(k), kZ + dz};
        cloud.points.push_back(p);
      }
    };
    add(60, 0.1);
    add(6, 1.5);
    add(3, -8);
    for (int i = 0; i < 2; ++i) {
      CloudPoint p;
      p.position = {kX0 + 40 + i, kY0 + 5, kZ};
      cloud.points.push_back(p);
    }
    WritePly(dir_ / "cloud.ply", cloud);
  }
};

TEST_F(CliEvaluateTest, PrintsOneRowPerThresholdAndWritesJsonAndPlots) {
  const auto r =
      RunCli("evaluate " + (dir_ / "cloud.ply").string() + " --reference " +
             (dir_ / "lidar.las").string() + " --drop-above 1,2 --json " +
             (dir_ / "report.json").string() + " --plots " + (dir_ / "plots").string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  // The header and exactly three rows: no threshold, T1 and T2.
  ASSERT_EQ(LinesStartingWith(r.out, "threshold").size(), 1u) << r.out;
  const auto none = LinesStartingWith(r.out, "none ");
  const auto t1 = LinesStartingWith(r.out, "|dz| <= 1 ");
  const auto t2 = LinesStartingWith(r.out, "|dz| <= 2 ");
  ASSERT_EQ(none.size() + t1.size() + t2.size(), 3u) << r.out;
  ASSERT_EQ(LinesStartingWith(r.out, "|dz|").size(), 2u) << r.out;
  EXPECT_NE(none[0].find(" 69 "), std::string::npos) << none[0];
  EXPECT_NE(t1[0].find(" 60 "), std::string::npos) << t1[0];
  EXPECT_NE(t2[0].find(" 66 "), std::string::npos) << t2[0];
  EXPECT_NE(r.out.find("radius d      1 (2 x the LiDAR's median nearest-neighbour XY spacing)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("no reference  2 of 71 points"), std::string::npos) << r.out;

  std::ifstream in(dir_ / "report.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["rows"].size(), 3u);
  EXPECT_TRUE(j["rows"][0]["threshold"].is_null());
  EXPECT_EQ(j["rows"][0]["checkpoints"], 69);
  EXPECT_EQ(j["rows"][1]["threshold"], 1.0);
  EXPECT_EQ(j["rows"][1]["dropped"], 9);
  EXPECT_EQ(j["rows"][2]["checkpoints"], 66);
  const double rmse2 = std::sqrt((60 * 0.01 + 6 * 2.25) / 66);
  EXPECT_NEAR(j["rows"][2]["rmse"].get<double>(), rmse2, 1e-9);
  EXPECT_EQ(j["without_reference"], 2);
  EXPECT_EQ(j["reference"]["kind"], "lidar");
  EXPECT_NEAR(j["reference"]["radius"].get<double>(), 1.0, 1e-9);

  for (const char* name : {"dz_histogram.png", "dz_map.png", "pseudo_errors.png"}) {
    const cv::Mat img = cv::imread((dir_ / "plots" / name).string(), cv::IMREAD_COLOR);
    EXPECT_FALSE(img.empty()) << name;
    EXPECT_GT(img.cols, 300) << name;
    EXPECT_GT(img.rows, 200) << name;
  }
  // Nothing but the outputs: no temporary file left behind.
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir_)) files += e.is_regular_file();
  EXPECT_EQ(files, 2 + 1 + 3);
}

TEST_F(CliEvaluateTest, DsmReferenceWithAFootprintReportsCompleteness) {
  GeoRaster dsm;
  dsm.width = dsm.height = 40;
  dsm.origin_x = kX0;
  dsm.origin_y = kY0 + 20;
  dsm.cell_size = 0.5;
  dsm.values.assign(40 * 40, static_cast<float>(kZ));
  dsm.crs = "EPSG:32632";
  WriteGeoTiff(dir_ / "dsm.tif", dsm);
  const auto r = RunCli("evaluate " + (dir_ / "cloud.ply").string() + " --reference " +
                        (dir_ / "dsm.tif").string() + " --footprint=" + std::to_string(kX0) + "," +
                        std::to_string(kY0) + "," + std::to_string(kX0 + 20) + "," +
                        std::to_string(kY0 + 20) + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(LinesStartingWith(r.out, "none ").size(), 1u) << r.out;
  EXPECT_EQ(LinesStartingWith(r.out, "|dz|").size(), 0u) << r.out;
  // The first 60 points are within the tolerance; count their cells here.
  std::set<std::pair<int, int>> cells;
  for (int k = 0; k < 60; ++k) {
    cells.insert(
        {static_cast<int>(std::floor(Dx(k) / 0.5)), static_cast<int>(std::floor(Dy(k) / 0.5))});
  }
  EXPECT_NE(r.out.find(": " + std::to_string(cells.size()) + " of 1600 non-empty DSM cells"),
            std::string::npos)
      << r.out;
}

// --run: the evaluation goes into a run's folder and its report.html.
TEST_F(CliEvaluateTest, RunPutsTheEvaluationInTheRunsReport) {
  const fs::path run = dir_ / "run";
  fs::create_directories(run);
  const std::string command = "evaluate " + (dir_ / "cloud.ply").string() + " --reference " +
                              (dir_ / "lidar.las").string() + " -q --run " + run.string();
  // Not a run's folder: refused before any work, naming it.
  auto r = RunCli(command);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find(run.string() + ": --run expects a folder"), std::string::npos) << r.err;
  std::ofstream(run / "report.json") << R"({"report_version": 2, "groups": [], "points": 71})";
  r = RunCli(command);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(run / "evaluation.json");
  EXPECT_EQ(nlohmann::json::parse(in)["rows"][0]["checkpoints"], 69);
  for (const char* name : {"dz_histogram.png", "dz_map.png", "pseudo_errors.png"}) {
    EXPECT_TRUE(fs::exists(run / "evaluation" / name)) << name;
  }
  const std::string page = test::Slurp(run / "report.html");
  EXPECT_NE(page.find("id=\"evaluation\""), std::string::npos);
  EXPECT_NE(page.find(">69<"), std::string::npos);  // the checkpoints, no threshold
}

TEST_F(CliEvaluateTest, MissingFileIsOneLineAndExitCode1) {
  const auto r =
      RunCli("evaluate /nonexistent/cloud.ply --reference " + (dir_ / "lidar.las").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/nonexistent/cloud.ply"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST_F(CliEvaluateTest, BadOptionIsOneLineAndExitCode1) {
  const auto r = RunCli("evaluate " + (dir_ / "cloud.ply").string() + " --reference " +
                        (dir_ / "lidar.las").string() + " --drop-above 2,0");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--drop-above 0"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace sapmvs

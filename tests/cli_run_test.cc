#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "cl_runtime.h"
#include "cli_test_util.h"
#include "sapmvs/cloud_merge.h"
#include "sapmvs/error.h"
#include "sapmvs/ply_io.h"
#include "sapmvs/simulate.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::HaveOpenClDevice;
using test::RunCli;

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

  // The outputs and one group's checkpoint, no temporary file left behind.
  std::set<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(out_)) {
    if (e.is_regular_file()) files.insert(fs::relative(e.path(), out_).string());
  }
  const std::set<std::string> expected = {".sapmvs_run",  // the folder's marker and lock
                                          "cloud.ply",
                                          "cloud.las",
                                          "dsm.tif",
                                          "dsm_color.tif",
                                          "dsm.png",
                                          "dsm.pgw",
                                          "report.json",
                                          "groups/plan.json",
                                          "groups/group_001.ply",
                                          "groups/group_001.json"};
  EXPECT_EQ(files, expected);
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

// --format, --image-dir, --no-size-check and --ground-height are info's
// block flags, and reach the reader: an empty image folder fails naming it,
// an unknown format or an infinite height fails naming the value, and the
// block's own folder given explicitly (with its format) runs.
TEST_F(CliRunTest, TakesInfosBlockFlags) {
  const fs::path empty = *root_ / "empty_images";
  fs::create_directories(empty);
  const std::string run = "run " + Block().string() + " --out " + out_.string();
  const auto no_images = RunCli(run + " --image-dir " + empty.string());
  EXPECT_NE(no_images.exit_code, 0);
  EXPECT_EQ(test::CountLines(no_images.err), 1) << no_images.err;
  EXPECT_NE(no_images.err.find(empty.string()), std::string::npos) << no_images.err;
  EXPECT_TRUE(NoOutput());
  const auto bad_format = RunCli(run + " --format bogus");
  EXPECT_NE(bad_format.exit_code, 0);
  EXPECT_EQ(test::CountLines(bad_format.err), 1) << bad_format.err;
  EXPECT_NE(bad_format.err.find("bogus"), std::string::npos) << bad_format.err;
  EXPECT_TRUE(NoOutput());
  const auto bad_height = RunCli(run + " --ground-height inf");
  EXPECT_NE(bad_height.exit_code, 0);
  EXPECT_EQ(test::CountLines(bad_height.err), 1) << bad_height.err;
  EXPECT_NE(bad_height.err.find("ground height"), std::string::npos) << bad_height.err;
  EXPECT_TRUE(NoOutput());
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const auto r = RunCli(run + " --format yaml --image-dir " +
                        (Block().parent_path() / "images").string() + " --no-size-check -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out_ / "cloud.ply"));
}

TEST_F(CliRunTest, ProfilePrintsKernelTablesAndWritesThem) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const auto r = RunCli("run " + Block().string() + " --out " + out_.string() + " --profile -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("profile: kernels"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("patch_refine"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("profile: phases"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(out_ / "profile.csv"));
  std::ifstream in(out_ / "profile.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  double device = 0;
  for (const auto& k : j.at("kernels")) device += k.at("seconds").get<double>();
  EXPECT_GT(device, 0) << "the queue did not profile";
  // Without --profile the queue does not profile: no device times at all.
  const fs::path plain = out_ / "plain";
  const auto p = RunCli("run " + Block().string() + " --out " + plain.string() + " -q");
  ASSERT_EQ(p.exit_code, 0) << p.err;
  std::ifstream rin(plain / "report.json");
  const nlohmann::json report = nlohmann::json::parse(rin);
  for (const auto& k : report.at("kernels")) EXPECT_EQ(k.at("device_seconds").get<double>(), 0);
  EXPECT_FALSE(fs::exists(plain / "profile.csv"));
}

// Whole-block runs: the tiny block (2 strips of 2 images) split into one
// group per strip by --max-images 3, matched with min_image_num 2.
class CliBlockRunTest : public CliRunTest {
 protected:
  static std::string Args(const fs::path& out, const std::string& more = "") {
    return "run " + Block().string() + " --out " + out.string() +
           " --min-image-num 2 --max-images 3 -q " + more;
  }
  static std::string Bytes(const fs::path& path) {
    std::ifstream f(path, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
  }
  static nlohmann::json Report(const fs::path& out) {
    std::ifstream in(out / "report.json");
    return nlohmann::json::parse(in);
  }
};

TEST_F(CliBlockRunTest, ResumedRunWritesTheSameCloud) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const fs::path whole = out_ / "whole", parts = out_ / "parts";
  const auto a = RunCli(Args(whole));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const nlohmann::json ja = Report(whole);
  ASSERT_EQ(ja.at("groups").size(), 2u) << ja.at("groups");

  // Stopped after one group: its checkpoint only, no final output.
  const auto b1 = RunCli(Args(parts, "--max-groups 1"));
  ASSERT_EQ(b1.exit_code, 0) << b1.err;
  EXPECT_NE(b1.out.find("resume"), std::string::npos) << b1.out;
  EXPECT_TRUE(fs::exists(parts / "groups" / "group_001.json"));
  EXPECT_FALSE(fs::exists(parts / "groups" / "group_002.json"));
  EXPECT_FALSE(fs::exists(parts / "cloud.ply"));
  // Resumed: the first group comes from its checkpoint, and the final cloud
  // is the uninterrupted run's, byte for byte.
  const auto b2 = RunCli(Args(parts));
  ASSERT_EQ(b2.exit_code, 0) << b2.err;
  const nlohmann::json jb = Report(parts);
  EXPECT_TRUE(jb.at("groups")[0].at("from_checkpoint").get<bool>());
  EXPECT_FALSE(jb.at("groups")[1].at("from_checkpoint").get<bool>());
  const std::string cloud_a = Bytes(whole / "cloud.ply");
  ASSERT_FALSE(cloud_a.empty());
  EXPECT_TRUE(cloud_a == Bytes(parts / "cloud.ply")) << "resumed cloud differs";
  EXPECT_EQ(ja.at("points"), jb.at("points"));

  // A run with other options does not mix its groups with these.
  const auto c = RunCli(Args(parts, "--threshold 0.8"));
  EXPECT_EQ(c.exit_code, 1);
  EXPECT_EQ(test::CountLines(c.err), 1) << c.err;
  EXPECT_NE(c.err.find("plan.json"), std::string::npos) << c.err;
  EXPECT_NE(c.err.find("--restart"), std::string::npos) << c.err;
  const auto d = RunCli(Args(parts, "--threshold 0.8 --restart"));
  EXPECT_EQ(d.exit_code, 0) << d.err;
  EXPECT_FALSE(Report(parts).at("groups")[0].at("from_checkpoint").get<bool>());
}

TEST_F(CliBlockRunTest, MergedCloudHasNoCrossGroupDuplicates) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  const auto r = RunCli(Args(out_));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = Report(out_);
  const PointCloud cloud = ReadPly(out_ / "cloud.ply");
  // The merged file lists each group's kept points in group order.
  std::vector<int> group_of;
  long input = 0;
  for (size_t g = 0; g < j.at("groups").size(); ++g) {
    group_of.insert(group_of.end(), j.at("groups")[g].at("kept_after_merge").get<long>(),
                    static_cast<int>(g));
    input += j.at("groups")[g].at("points").get<long>();
  }
  ASSERT_EQ(group_of.size(), cloud.points.size());
  EXPECT_EQ(j.at("merge").at("input").get<long>(), input);
  // Both groups contribute, and the overlap had duplicates to drop.
  EXPECT_GT(j.at("groups")[0].at("kept_after_merge").get<long>(), 0);
  EXPECT_GT(j.at("groups")[1].at("kept_after_merge").get<long>(), 0);
  EXPECT_GT(j.at("merge").at("cross_group_duplicates").get<long>(), 0);
  // No two points of different groups within 0.25 GSD (the tiny block's GSD
  // is 0.2727 m at full resolution).
  EXPECT_EQ(CountCrossGroupPairs(cloud, group_of, 0.25 * 0.2727), 0);
  // The paper's statistics are in the report.
  EXPECT_GT(j.at("mean_point_spacing").get<double>(), 0);
  EXPECT_GT(j.at("density_per_unit2").get<double>(), 0);
  EXPECT_EQ(j.at("grouping"), "strip");
  EXPECT_NE(r.out.find("avg. distance"), std::string::npos) << r.out;
}

TEST_F(CliBlockRunTest, DsmIsReadByGdalinfoWithTheBlocksCrsAndTheCloudsExtent) {
  if (!HaveOpenClDevice()) GTEST_SKIP() << "no OpenCL device on this machine";
  if (std::system("gdalinfo --version >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gdalinfo missing (Debian package gdal-bin)";
  }
  const auto r = RunCli(Args(out_));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const fs::path json = out_ / "gdalinfo.json";
  const std::string cmd =
      "gdalinfo -json " + (out_ / "dsm.tif").string() + " > " + json.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("driverShortName"), "GTiff");
  const std::string wkt = j.at("coordinateSystem").at("wkt").get<std::string>();
  EXPECT_NE(wkt.find("32632"), std::string::npos) << wkt;  // the tiny block's UTM 32N
  const PointCloud cloud = ReadPly(out_ / "cloud.ply");
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const CloudPoint& p : cloud.points) {
    xmin = std::min(xmin, p.position.x());
    xmax = std::max(xmax, p.position.x());
    ymin = std::min(ymin, p.position.y());
    ymax = std::max(ymax, p.position.y());
  }
  const auto& corners = j.at("cornerCoordinates");
  const double ulx = corners.at("upperLeft")[0], uly = corners.at("upperLeft")[1];
  const double lrx = corners.at("lowerRight")[0], lry = corners.at("lowerRight")[1];
  const double cell = j.at("geoTransform")[1];
  EXPECT_LE(ulx, xmin);
  EXPECT_GT(ulx, xmin - cell);
  EXPECT_GE(uly, ymax);
  EXPECT_LT(uly, ymax + cell);
  EXPECT_GE(lrx, xmax);
  EXPECT_LT(lrx, xmax + cell + 1e-9);
  EXPECT_LE(lry, ymin);
  EXPECT_GT(lry, ymin - cell - 1e-9);
  // The cell defaults to twice the mean point spacing, as the report says.
  EXPECT_NEAR(cell, Report(out_).at("dsm_cell").get<double>(), 1e-9);
}

}  // namespace
}  // namespace sapmvs

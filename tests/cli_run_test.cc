#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "cli_test_util.h"
#include "device/cl_devices.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/cloud_merge.h"
#include "sapmvs/run/run_options.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::HaveOpenClDevice;
using test::RunCli;

class CliRunTest : public ::testing::Test {
 protected:
  // Outputs in a folder unique to the process; the tiny block is shared.
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("sapmvs_cli_run_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    fs::create_directories(*root_);
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

  static fs::path Block() { return test::Simulated("tiny", 1) / "block.yaml"; }
  // For the flags refused before the block is read: no block to simulate,
  // and a run that read it first would fail naming it instead.
  static fs::path NoBlock() { return *root_ / "no_block" / "block.yaml"; }
  // Nothing at all under the output folder (or no folder).
  bool NoOutput() const { return !fs::exists(out_) || fs::is_empty(out_); }

  static fs::path* root_;
  fs::path out_;
};

fs::path* CliRunTest::root_ = nullptr;

// `run` has some 40 flags: its help shows them in sections, with examples.
TEST(CliRunHelp, ShowsSectionsAndExamples) {
  const auto r = RunCli("run --help");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  size_t last = 0;
  // The sections in the order a user meets them, each with one of its flags.
  for (const auto& [section, flag] :
       std::vector<std::pair<std::string, std::string>>{{"Input:", "--image-dir"},
                                                        {"Output and resume:", "--restart"},
                                                        {"Matching:", "--level"},
                                                        {"Device:", "--device"},
                                                        {"Seeds and edges:", "--edges"},
                                                        {"Propagation:", "--max-wave"},
                                                        {"Filter:", "--min-cluster"},
                                                        {"Grouping:", "--memory-budget"},
                                                        {"Merge and DSM:", "--dsm-cell"}}) {
    const size_t at = r.out.find("\n" + section + "\n");
    ASSERT_NE(at, std::string::npos) << section << " missing in:\n" << r.out;
    EXPECT_GT(at, last) << section << " out of order";
    last = at;
    const size_t next = r.out.find(":\n", at + section.size() + 2);
    const std::string body = r.out.substr(at, next == std::string::npos ? next : next - at);
    EXPECT_NE(body.find(flag), std::string::npos) << flag << " not under " << section;
  }
  EXPECT_NE(r.out.find("Examples:\n  sapmvs run block.yaml --out"), std::string::npos) << r.out;
}

// report.json's provenance, machine, device, CRS and bounds, against the
// cloud the run wrote.
void ExpectRunProvenance(const nlohmann::json& j, const PointCloud& cloud) {
  EXPECT_EQ(j.at("report_version"), 2);
  EXPECT_EQ(j.at("sapmvs").at("version"), SAPMVS_VERSION);
  const std::string commit = j.at("sapmvs").at("commit");
  EXPECT_TRUE(commit == "unknown" || std::regex_match(commit, std::regex("[0-9a-f]{7,40}")))
      << commit;
  const auto& cmd = j.at("command_line");
  ASSERT_TRUE(cmd.is_array());
  ASSERT_GE(cmd.size(), 4u) << cmd;
  EXPECT_EQ(fs::path(cmd.at(0).get<std::string>()).filename(), "sapmvs") << cmd;
  EXPECT_EQ(cmd.at(1), "run") << cmd;
  // ISO 8601 UTC; in that form text order is time order.
  const std::regex iso(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z)");
  const std::string start = j.at("start_time"), end = j.at("end_time");
  EXPECT_TRUE(std::regex_match(start, iso)) << start;
  EXPECT_TRUE(std::regex_match(end, iso)) << end;
  EXPECT_LE(start, end);
  const auto& m = j.at("machine");
  EXPECT_FALSE(m.at("hostname").get<std::string>().empty());
  EXPECT_TRUE(m.at("cpu").is_string());
  EXPECT_GE(m.at("cores").get<int>(), 1);
  EXPECT_GE(m.at("threads").get<int>(), 1);
  EXPECT_GT(m.at("memory_bytes").get<double>(), 64.0 * (1 << 20));
  const auto& d = j.at("device");
  for (const char* key : {"name", "vendor", "platform", "type", "description"}) {
    EXPECT_FALSE(d.at(key).get<std::string>().empty()) << key << " in " << d;
  }
  // The tiny block is in UTM 32N.
  EXPECT_EQ(j.at("crs").at("epsg"), 32632) << j.at("crs");
  EXPECT_NE(j.at("crs").at("name").get<std::string>().find("UTM zone 32N"), std::string::npos);
  Eigen::Vector3d lo, hi;
  for (int a = 0; a < 3; ++a) {
    const char* axis = a == 0 ? "x" : a == 1 ? "y" : "z";
    lo[a] = j.at("bounds").at("min").at(axis);
    hi[a] = j.at("bounds").at("max").at(axis);
  }
  Eigen::Vector3d cloud_lo = cloud.points.front().position, cloud_hi = cloud_lo;
  for (const CloudPoint& p : cloud.points) {
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(p.position[a], lo[a]) << "axis " << a;
      ASSERT_LE(p.position[a], hi[a]) << "axis " << a;
    }
    cloud_lo = cloud_lo.cwiseMin(p.position);
    cloud_hi = cloud_hi.cwiseMax(p.position);
  }
  // Tight: the box is the cloud's, not some padded extent.
  EXPECT_LT((cloud_lo - lo).norm(), 1e-6);
  EXPECT_LT((cloud_hi - hi).norm(), 1e-6);
  // Without --profile no device time was measured, and none is reported.
  for (const auto& k : j.at("kernels")) EXPECT_FALSE(k.contains("device_seconds")) << k;
  for (const auto& st : j.at("stages")) EXPECT_FALSE(st.contains("device_seconds")) << st;
}

TEST_F(CliRunTest, WritesCloudAndReport) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto [out, r] = test::SharedRun(Block(), "-q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("cloud.ply"), std::string::npos) << r.out;

  const PointCloud cloud = ReadPly(out / "cloud.ply");
  ASSERT_GT(cloud.points.size(), 0u);
  EXPECT_TRUE(cloud.has_normals);
  EXPECT_TRUE(cloud.has_colors);
  EXPECT_TRUE(cloud.has_scores);
  EXPECT_TRUE(cloud.has_views);
  EXPECT_FALSE(cloud.crs.empty());
  EXPECT_NE(cloud.crs.find("32632"), std::string::npos) << cloud.crs;  // the tiny block's CRS
  // Default min_image_num is 3.
  for (const CloudPoint& p : cloud.points) ASSERT_GE(p.num_views, 3);

  std::ifstream in(out / "report.json");
  ASSERT_TRUE(in) << "no report.json";
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("points").get<long>(), static_cast<long>(cloud.points.size()));
  EXPECT_EQ(j.at("mode"), "sapmvs");
  EXPECT_EQ(j.at("level"), 1);
  EXPECT_EQ(j.at("images"), 4);
  // `plan` with the same flags shows the groups the run matched.
  const fs::path plan_json = *root_ / "plan.json";  // not among the run's files
  const auto plan = RunCli("plan " + Block().string() + " --json " + plan_json.string());
  ASSERT_EQ(plan.exit_code, 0) << plan.err;
  std::ifstream plan_in(plan_json);
  const nlohmann::json p = nlohmann::json::parse(plan_in);
  ASSERT_EQ(p.at("groups").size(), j.at("groups").size()) << p.at("groups");
  for (size_t g = 0; g < p.at("groups").size(); ++g) {
    EXPECT_EQ(p.at("groups")[g].at("names"), j.at("groups")[g].at("images"));
  }
  ASSERT_TRUE(j.at("stages").is_array());
  ASSERT_FALSE(j.at("stages").empty());
  double matching_cpu = 0, run_cpu = 0;
  for (const auto& stage : j.at("stages")) {
    EXPECT_TRUE(stage.at("stage").is_string()) << stage;
    ASSERT_TRUE(stage.at("wall_seconds").is_number()) << stage;
    EXPECT_GE(stage.at("wall_seconds").get<double>(), 0.0) << stage;
    // Every stage says how busy it kept the cores, the matching stages and
    // the run's own ("run merge", ...).
    ASSERT_TRUE(stage.contains("cpu_seconds")) << stage;
    EXPECT_GE(stage.at("cpu_seconds").get<double>(), 0.0) << stage;
    const bool matching = stage.at("stage").get<std::string>().rfind("run ", 0) != 0;
    if (matching) matching_cpu += stage.at("cpu_seconds").get<double>();
    if (!matching) run_cpu += stage.at("cpu_seconds").get<double>();
  }
  EXPECT_GT(matching_cpu, 0.0) << j.at("stages");
  EXPECT_GT(run_cpu, 0.0) << j.at("stages");
  ASSERT_TRUE(j.at("kernels").is_array());
  ASSERT_FALSE(j.at("kernels").empty());
  bool launched = false;
  for (const auto& kernel : j.at("kernels")) {
    EXPECT_TRUE(kernel.at("kernel").is_string()) << kernel;
    launched = launched || kernel.at("launches").get<long>() > 0;
  }
  EXPECT_TRUE(launched) << j.at("kernels");
  ExpectRunProvenance(j, cloud);

  // The outputs and one group's checkpoint, no temporary file left behind.
  std::set<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    if (e.is_regular_file()) files.insert(fs::relative(e.path(), out).string());
  }
  const std::set<std::string> expected = {".sapmvs_run",  // the folder's marker and lock
                                          "cloud.ply",
                                          "cloud.las",
                                          "dsm.tif",
                                          "dsm_color.tif",
                                          "dsm.png",
                                          "dsm.pgw",
                                          "ortho.tif",
                                          "ortho.png",
                                          "ortho.pgw",
                                          "report.json",
                                          "report.html",
                                          "groups/plan.json",
                                          "groups/group_001.ply",
                                          "groups/group_001.json"};
  EXPECT_EQ(files, expected);
}

// Each group's measured peak sits beside the plan's estimate, within the
// 25 % the estimate is meant to hold; a budget below the default group
// splits the block, and the run stays within it (plus 10 %).
TEST_F(CliRunTest, MemoryEstimateHoldsAndABudgetSplitsTheBlock) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  auto check_groups = [](const nlohmann::json& report) {
    for (const auto& g : report.at("groups")) {
      const double estimate = g.at("memory_estimate_bytes").at("total").get<double>();
      const auto& measured = g.at("memory_measured_bytes");
      const double peak = measured.at("peak_rss").get<double>();
      EXPECT_GT(measured.at("rss_before").get<double>(), 0) << g;
      EXPECT_LE(measured.at("rss_before").get<double>(), peak) << g;
      EXPECT_GT(measured.at("device_peak").get<double>(), 0) << g;
      EXPECT_NEAR(estimate / peak, 1.0, 0.25) << g;
    }
  };
  const auto [out, r] = test::SharedRun(Block(), "-q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(out / "report.json");
  const nlohmann::json whole = nlohmann::json::parse(in);
  ASSERT_EQ(whole.at("groups").size(), 1u);
  check_groups(whole);

  // A budget between what a group of 2 and a group of 4 need, at level 0
  // (at level 1 an image of this block adds only about 1.4 MiB to an
  // estimate, at level 0 about 5.5 MiB): the budget lies at least 5 MiB
  // from either group's estimate, where the process's RSS, which every
  // estimate includes, drifts by 0.2 MiB between runs. Two groups of 2 (one
  // per strip, --min-image-num 2), with what views still fit.
  const fs::path whole_out = *root_ / "budget_whole";  // not among the split run's files
  const auto whole_l0 = RunCli("run " + Block().string() + " --out " + whole_out.string() +
                               " --level 0 --restart -q");
  ASSERT_EQ(whole_l0.exit_code, 0) << whole_l0.err;
  std::ifstream whole_in(whole_out / "report.json");
  const nlohmann::json four = nlohmann::json::parse(whole_in);
  ASSERT_EQ(four.at("groups").size(), 1u);
  check_groups(four);
  const auto& estimate = four.at("groups")[0].at("memory_estimate_bytes");
  const fs::path two_json = *root_ / "budget_two.json";
  const auto plan_two = RunCli("plan " + Block().string() +
                               " --level 0 --max-images 2 --min-image-num 2 --strip-views 0 "
                               "--tile-extra-views 0 "
                               "--json " +
                               two_json.string());
  ASSERT_EQ(plan_two.exit_code, 0) << plan_two.err;
  std::ifstream two_in(two_json);
  const nlohmann::json two_plan = nlohmann::json::parse(two_in);
  const auto& two = two_plan.at("groups").at(0).at("memory");
  const double four_adds = estimate.at("host").get<double>();
  const double two_adds = two.at("host_bytes").get<double>();
  ASSERT_GT(four_adds - two_adds, 10.0 * (1 << 20)) << "two images at level 0 add too little";
  const double budget = estimate.at("total").get<double>() - 0.5 * (four_adds - two_adds);
  const auto split = RunCli("run " + Block().string() + " --out " + out_.string() +
                            " --level 0 --min-image-num 2 -q --memory-budget " +
                            std::to_string(static_cast<long>(budget)));
  ASSERT_EQ(split.exit_code, 0) << split.err;
  std::ifstream split_in(out_ / "report.json");
  const nlohmann::json parts = nlohmann::json::parse(split_in);
  EXPECT_GE(parts.at("groups").size(), 2u);
  check_groups(parts);
  for (const auto& part : parts.at("groups")) {
    EXPECT_LE(part.at("memory_estimate_bytes").at("total").get<double>(), budget) << part;
  }
  EXPECT_LE(parts.at("peak_rss_bytes").get<double>(), 1.1 * budget);
}

// An ODM project (reference_lla, no CRS of its own) comes out in UTM 51N:
// `info` says so, and cloud.las, dsm.tif and report.json carry EPSG:32651.
TEST_F(CliRunTest, OdmProjectOutputsCarryItsEpsgCode) {
  const fs::path odm = test::SharedDir() / "datasets/orthority_ngi_odm/odm";
  SAPMVS_REQUIRE_PATH(odm / "opensfm/reconstruction.json");
  const auto info = RunCli("info " + odm.string() + " --ground-height 98");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("frame          CRS EPSG:32651 ("), std::string::npos) << info.out;
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli("run " + odm.string() + " --ground-height 98 --level 2 --out " +
                        out_.string() + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const GeoRaster dsm = ReadGeoRaster(out_ / "dsm.tif");
  EXPECT_EQ(dsm.crs, CrsToWkt("EPSG:32651"));
  EXPECT_EQ(ReadLas(out_ / "cloud.las").crs_wkt, CrsToWkt("EPSG:32651"));
  std::ifstream report(out_ / "report.json");
  EXPECT_EQ(nlohmann::json::parse(report).at("crs").at("epsg"), 32651);
}

// GDAL and the hundred libraries it loads are mapped only when a step needs
// them (cli/gdal_module.h): the binary does not link them, and a run on PNG
// images without a DEM loads the module only after its matching, to write
// its rasters; its CRS is checked before, in a child process.
TEST_F(CliRunTest, LoadsGdalOnlyForTheOutputs) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto linked = test::RunCommand("LD_TRACE_LOADED_OBJECTS=1 " + test::CliPath().string());
  ASSERT_EQ(linked.exit_code, 0) << linked.err;
  EXPECT_NE(linked.out.find("libopencv_core"), std::string::npos) << linked.out;
  EXPECT_EQ(linked.out.find("libgdal"), std::string::npos) << linked.out;
  EXPECT_EQ(linked.out.find("libsapmvs_gdal"), std::string::npos) << linked.out;

  // The tiny block without its DEM, which GDAL would read before the matching.
  const fs::path sim = Block().parent_path();
  std::istringstream in(test::Slurp(Block()));
  std::string yaml;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("dem:", 0) == 0) continue;
    if (line == "images: images") line = "images: " + (sim / "images").string();
    if (line == "  file: orientation.txt") line = "  file: " + (sim / "orientation.txt").string();
    yaml += line + "\n";
  }
  const fs::path block = *root_ / "no_dem" / "block.yaml";
  fs::create_directories(block.parent_path());
  std::ofstream(block) << yaml;
  const auto r =
      RunCli("run " + block.string() + " --out " + out_.string() + " -q -v", "LD_DEBUG=files");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const size_t merged = r.err.find("run: merge");
  const size_t module = r.err.find("libsapmvs_gdal.so");
  ASSERT_NE(merged, std::string::npos) << r.err;
  ASSERT_NE(module, std::string::npos) << "the outputs need GDAL";
  EXPECT_GT(module, merged) << "GDAL loaded before the matching ended";
  EXPECT_TRUE(fs::exists(out_ / "dsm.tif"));
}

TEST_F(CliRunTest, MinImageNumTwoIsAccepted) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
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
  const auto r = RunCli("run " + NoBlock().string() + " --out " + out_.string() + " --mode foo");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("'foo'"), std::string::npos) << r.err;
  EXPECT_TRUE(NoOutput());
}

TEST_F(CliRunTest, NegativeLevelIsOneLineNamingIt) {
  const auto r = RunCli("run " + NoBlock().string() + " --out " + out_.string() + " --level -1");
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
  const std::string no_block = "run " + NoBlock().string() + " --out " + out_.string();
  const auto bad_format = RunCli(no_block + " --format bogus");
  EXPECT_NE(bad_format.exit_code, 0);
  EXPECT_EQ(test::CountLines(bad_format.err), 1) << bad_format.err;
  EXPECT_NE(bad_format.err.find("bogus"), std::string::npos) << bad_format.err;
  EXPECT_TRUE(NoOutput());
  const auto bad_height = RunCli(no_block + " --ground-height inf");
  EXPECT_NE(bad_height.exit_code, 0);
  EXPECT_EQ(test::CountLines(bad_height.err), 1) << bad_height.err;
  EXPECT_NE(bad_height.err.find("ground height"), std::string::npos) << bad_height.err;
  EXPECT_TRUE(NoOutput());
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli(run + " --format yaml --image-dir " +
                        (Block().parent_path() / "images").string() + " --no-size-check -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(out_ / "cloud.ply"));
}

TEST_F(CliRunTest, ProfilePrintsKernelTablesAndWritesThem) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
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
  // With it, report.json has the device times it measured.
  std::ifstream pin(out_ / "report.json");
  const nlohmann::json profiled = nlohmann::json::parse(pin);
  double reported = 0;
  for (const auto& k : profiled.at("kernels")) reported += k.at("device_seconds").get<double>();
  EXPECT_GT(reported, 0);
  // Without --profile the queue does not profile: no device times at all,
  // not even zeros. -v shows the stages' times as they end.
  const fs::path plain = out_ / "plain";
  const auto p = RunCli("run " + Block().string() + " --out " + plain.string() + " -q -v");
  ASSERT_EQ(p.exit_code, 0) << p.err;
  std::ifstream rin(plain / "report.json");
  const nlohmann::json report = nlohmann::json::parse(rin);
  for (const auto& k : report.at("kernels")) EXPECT_FALSE(k.contains("device_seconds")) << k;
  EXPECT_FALSE(fs::exists(plain / "profile.csv"));
  for (const std::string line : {"device: ", "run: plan ", "group 1/1: seeds ", "run: write "}) {
    EXPECT_NE(p.err.find(line), std::string::npos) << line << " in\n" << p.err;
  }
  EXPECT_EQ(p.err.find("in kernels"), std::string::npos) << p.err;
}

// Whole-block runs: the tiny block (2 strips of 2 images) split into one
// group per strip by --strategy strip --max-images 3, matched with
// min_image_num 2.
class CliBlockRunTest : public CliRunTest {
 protected:
  static constexpr const char* kArgs = "--strategy strip --min-image-num 2 --max-images 3 -q";
  static std::string Args(const fs::path& out, const std::string& more = "") {
    return "run " + Block().string() + " --out " + out.string() + " " + kArgs + " " + more;
  }
  // The run of Args(), shared by the tests that only read it.
  static test::SharedRunResult Shared() { return test::SharedRun(Block(), kArgs); }
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
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto [whole, a] = Shared();
  const fs::path parts = out_ / "parts";
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const nlohmann::json ja = Report(whole);
  ASSERT_EQ(ja.at("groups").size(), 2u) << ja.at("groups");
  // The images the groups shared at the level are the run's scratch.
  EXPECT_FALSE(fs::exists(whole / "groups" / "levels"));

  // Stopped after one group: its checkpoint only, no final output.
  const auto b1 = RunCli(Args(parts, "--max-groups 1"));
  ASSERT_EQ(b1.exit_code, 0) << b1.err;
  EXPECT_NE(b1.out.find("resume"), std::string::npos) << b1.out;
  EXPECT_TRUE(fs::exists(parts / "groups" / "group_001.json"));
  EXPECT_FALSE(fs::exists(parts / "groups" / "group_002.json"));
  EXPECT_FALSE(fs::exists(parts / "cloud.ply"));
  EXPECT_FALSE(fs::exists(parts / "groups" / "levels"));
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
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto [out, r] = Shared();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = Report(out);
  const PointCloud cloud = ReadPly(out / "cloud.ply");
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
  // is 0.2727 m at full resolution) but in the blend band by their border,
  // --seam-blend GSDs of level 1 wide, where the merge keeps both groups.
  std::vector<Eigen::Vector2d> centers;
  for (const auto& g : j.at("groups"))
    centers.emplace_back(g.at("center")[0].get<double>(), g.at("center")[1].get<double>());
  const double band = RunOptions().seam_blend_gsd * 2 * 0.2727;
  PointCloud beyond;
  std::vector<int> beyond_group;
  long in_band = 0;
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3d& p = cloud.points[i].position;
    if (CoreOwnerAndBorder(centers, p.x(), p.y()).second < band) {
      ++in_band;
      continue;
    }
    beyond.points.push_back(cloud.points[i]);
    beyond_group.push_back(group_of[i]);
  }
  EXPECT_GT(in_band, 0);
  EXPECT_EQ(CountCrossGroupPairs(beyond, beyond_group, 0.25 * 0.2727), 0);
  // The paper's statistics are in the report.
  EXPECT_GT(j.at("mean_point_spacing").get<double>(), 0);
  EXPECT_GT(j.at("density_per_unit2").get<double>(), 0);
  EXPECT_EQ(j.at("grouping"), "strip");
  EXPECT_NE(r.out.find("avg. distance"), std::string::npos) << r.out;
}

TEST_F(CliBlockRunTest, DsmIsReadByGdalinfoWithTheBlocksCrsAndTheCloudsExtent) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  if (std::system("gdalinfo --version >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gdalinfo missing (Debian package gdal-bin)";
  }
  const auto [out, r] = Shared();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  fs::create_directories(out_);
  const fs::path json = out_ / "gdalinfo.json";  // beside, not in, the shared run
  const std::string cmd =
      "gdalinfo -json " + (out / "dsm.tif").string() + " > " + json.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(json);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("driverShortName"), "GTiff");
  const std::string wkt = j.at("coordinateSystem").at("wkt").get<std::string>();
  EXPECT_NE(wkt.find("32632"), std::string::npos) << wkt;  // the tiny block's UTM 32N
  const PointCloud cloud = ReadPly(out / "cloud.ply");
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
  EXPECT_NEAR(cell, Report(out).at("dsm_cell").get<double>(), 1e-9);
}

}  // namespace
}  // namespace sapmvs

// profiling/versus_pmvs2, the benchmark behind profiling/results/versus_pmvs2.md,
// run end to end with a stand-in for PMVS2: PMVS2 is built by hand outside
// the tree (profiling/anchors/) and is not on CI's machines, so without this
// nothing but a person running it would notice the benchmark break. The
// stand-in is a shell script that checks what PMVS2 would read (its prefix
// and option file, the images and matrices, --threads in the option file)
// and writes a cloud in PMVS2's own PLY format: four points 100 m apart,
// three of them on its second run, so that the second run's row must show
// 75 % of the first run's points covered and all of its own near the first's.
// OpenMVS, the second anchor, gets stand-ins of the same kind.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test_util.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// What a second run writes differs, so that the two directions of coverage
// tell apart. PMVS2 is called as `pmvs2 PREFIX/ option`.
constexpr const char* kStandInPmvs2 = R"(#!/bin/sh
set -e
prefix="$1"; option="$2"
case "$prefix" in */) ;; *) echo "stand-in pmvs2: prefix $prefix lacks its trailing /" >&2; exit 2;; esac
test -f "$prefix$option" || { echo "stand-in pmvs2: no option file $prefix$option" >&2; exit 2; }
grep -qx "level 1" "$prefix$option" || { echo "stand-in pmvs2: option file without level 1" >&2; exit 2; }
grep -qx "CPU 1" "$prefix$option" || { echo "stand-in pmvs2: option file without CPU 1" >&2; exit 2; }
test -d "${prefix}models" || { echo "stand-in pmvs2: no models/" >&2; exit 2; }
cameras=$(ls "${prefix}txt" | grep -c '\.txt$')
images=$(ls "${prefix}visualize" | grep -c '\.jpg$')
test "$cameras" -gt 0 && test "$cameras" = "$images" || { echo "stand-in pmvs2: $cameras matrices, $images images" >&2; exit 2; }
case "$prefix" in */pmvs2_again/) n=3;; *) n=4;; esac
{
  printf 'ply\nformat ascii 1.0\nelement vertex %d\n' "$n"
  printf 'property float x\nproperty float y\nproperty float z\n'
  printf 'property float nx\nproperty float ny\nproperty float nz\n'
  printf 'property uchar diffuse_red\nproperty uchar diffuse_green\nproperty uchar diffuse_blue\n'
  printf 'property float quality\nend_header\n'
  printf '0 0 0 0 0 1 120 150 90 0.9\n100 0 0 0 0 1 120 150 90 0.9\n0 100 0 0 0 1 120 150 90 0.9\n'
  test "$n" = 4 && printf '100 100 0 0 0 1 120 150 90 0.9\n'
} > "${prefix}models/$option.ply"
echo "stand-in pmvs2: $n points"
)";

// Stand-ins for OpenMVS's two programs, which check what the real ones would
// be given and write, in OpenMVS's PLY layout (normals, colours, then its
// list properties), the stand-in PMVS2's four points in the COLMAP folder's
// frame: PMVS2's whole cloud covered by it, once each frame is right.
constexpr const char* kStandInInterfaceColmap = R"(#!/bin/sh
set -e
test "$1" = -i && test -d "$2/images" && test -d "$2/sparse" || { echo "stand-in InterfaceCOLMAP: -i $2 is no COLMAP folder" >&2; exit 2; }
test "$3" = -o && test "$5" = --image-folder && test "$6" = "$2/images/" && test "$7" = -w || { echo "stand-in InterfaceCOLMAP: arguments $*" >&2; exit 2; }
echo scene > "$4"
)";

constexpr const char* kStandInDensify = R"(#!/bin/sh
set -e
test "$1" = -i && test -f "$2" || { echo "stand-in DensifyPointCloud: no scene $2" >&2; exit 2; }
test "$5 $6 $7 $8 $9" = "--resolution-level 1 --max-threads 1 -w" || { echo "stand-in DensifyPointCloud: arguments $*" >&2; exit 2; }
shift 9
{
  printf 'ply\nformat ascii 1.0\nelement vertex 4\n'
  printf 'property float x\nproperty float y\nproperty float z\n'
  printf 'property float nx\nproperty float ny\nproperty float nz\n'
  printf 'property uchar red\nproperty uchar green\nproperty uchar blue\n'
  printf 'property list uchar uint view_indices\nproperty list uchar float points_weights\nend_header\n'
  printf '0 0 0 0 0 1 120 150 90 2 0 1 2 0.5 0.5\n100 0 0 0 0 1 120 150 90 1 2 1 1.0\n'
  printf '0 100 0 0 0 1 120 150 90 2 1 2 2 0.5 0.5\n100 100 0 0 0 1 120 150 90 0 0\n'
} > "$1/scene_dense.ply"
)";

// The cells of the markdown table's row whose first cell is `name`; empty
// when there is none.
std::vector<std::string> Row(const std::string& markdown, const std::string& name) {
  std::istringstream lines(markdown);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> cells;
    std::istringstream s(line);
    for (std::string cell; std::getline(s, cell, '|');) {
      const size_t a = cell.find_first_not_of(' '), b = cell.find_last_not_of(' ');
      cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
    }
    // "| name | ..." splits into "", "name", ...
    if (cells.size() > 2 && cells[0].empty() && cells[1] == name) {
      return {cells.begin() + 1, cells.end()};
    }
  }
  return {};
}

class VersusPmvs2Test : public test::ScratchTest {
 protected:
  void SetUp() override {
#ifndef SAPMVS_VERSUS_PMVS2_PATH
    GTEST_SKIP() << "versus_pmvs2 not built (SAPMVS_BUILD_BENCHMARKS=OFF)";
#else
    SAPMVS_REQUIRE_OPENCL_DEVICE();
    ScratchTest::SetUp();
    stand_in_ = dir_ / "pmvs2";
    std::ofstream(stand_in_) << kStandInPmvs2;
    fs::permissions(stand_in_, fs::perms::owner_all, fs::perm_options::add);
    block_ = test::Simulated("tiny", 1) / "block.yaml";
#endif
  }

  // versus_pmvs2 BLOCK --out dir_/out --threads THREADS ARGS, with the
  // stand-in.
  test::CliResult Versus(const std::string& args, int threads = 1) const {
#ifdef SAPMVS_VERSUS_PMVS2_PATH
    return test::RunCommand(std::string(SAPMVS_VERSUS_PMVS2_PATH) + " " + block_.string() +
                            " --out " + (dir_ / "out").string() + " --threads " +
                            std::to_string(threads) + " --sapmvs " + test::CliPath().string() +
                            " --pmvs2 " + stand_in_.string() + " " + args);
#else
    (void)args;
    (void)threads;
    return {};
#endif
  }

  fs::path stand_in_, block_;
};

TEST_F(VersusPmvs2Test, RunsPmvs2TwiceAndComparesEachCloudWithTheFirst) {
  const fs::path md = dir_ / "table.md";
  const test::CliResult r =
      Versus("--modes sapmvs --pmvs2-again --truth " +
             (block_.parent_path() / "truth" / "dsm.tif").string() + " --markdown " + md.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string markdown = test::Slurp(md);
  // The same table on stdout and in the file the benchmark appends to.
  EXPECT_NE(r.out.find(markdown), std::string::npos);

  const std::vector<std::string> first = Row(markdown, "PMVS2");
  const std::vector<std::string> second = Row(markdown, "PMVS2, second run");
  const std::vector<std::string> ours = Row(markdown, "sapmvs --mode sapmvs");
  ASSERT_FALSE(first.empty()) << markdown;
  ASSERT_EQ(second.size(), first.size()) << markdown;
  ASSERT_EQ(ours.size(), first.size()) << markdown;
  // Columns: tool, wall, CPU, CPU/wall, matching CPU/wall, steal, RSS, of it
  // files, of it anonymous, points, PMVS2->row at 1 and 2 GSD, row->PMVS2 at
  // 1 and 2 GSD, ...
  EXPECT_EQ(first[9], "4");
  EXPECT_EQ(second[9], "3");
  EXPECT_EQ(second[10], "75.0 %");
  EXPECT_EQ(second[11], "75.0 %");
  EXPECT_EQ(second[12], "100.0 %");
  EXPECT_EQ(second[13], "100.0 %");
  EXPECT_GT(std::stol(ours[9]), 1000);
  EXPECT_EQ(first[10], "–");
  // Both PMVS2 runs are timed; the stand-in's peak is a shell's, above zero.
  EXPECT_NE(first[1], "–");
  EXPECT_NE(second[1], "–");
  EXPECT_GT(std::stod(second[6]), 0);
  // sapmvs runs long enough to be sampled: PoCL's LLVM alone maps tens of
  // MiB of files; the two parts of a sample lie within the peak.
  EXPECT_GT(std::stod(ours[7]), 20) << ours[7];
  EXPECT_GT(std::stod(ours[8]), 0) << ours[8];
  EXPECT_LE(std::stod(ours[7]) + std::stod(ours[8]), std::stod(ours[6]) + 2);

  // The second table's last column, the work per point: counted for sapmvs
  // (its report.json), none for PMVS2.
  const std::string surface = markdown.substr(markdown.find("| tool / mode | points |"));
  const std::vector<std::string> our_work = Row(surface, "sapmvs --mode sapmvs");
  const std::vector<std::string> pmvs2_work = Row(surface, "PMVS2");
  ASSERT_FALSE(our_work.empty()) << surface;
  ASSERT_FALSE(pmvs2_work.empty()) << surface;
  EXPECT_GT(std::stod(our_work.back()), 1.0) << surface;
  EXPECT_EQ(pmvs2_work.back(), "–") << surface;

  // Against the truth, the last column: sapmvs's points lie on the true
  // surface, the stand-in's 100 m apart on the local frame's plane mostly
  // not.
  EXPECT_NE(ours.back(), "–");
  EXPECT_GT(std::stod(ours.back()), 90.0) << ours.back();

  // The second run read the first one's images and matrices through links and
  // its own copy of the option file, and wrote its own models/.
  const fs::path again = dir_ / "out" / "pmvs2_again";
  EXPECT_TRUE(fs::is_symlink(again / "visualize"));
  EXPECT_TRUE(fs::is_symlink(again / "txt"));
  EXPECT_FALSE(fs::is_symlink(again / "option"));
  EXPECT_FALSE(fs::is_symlink(again / "models"));
  EXPECT_TRUE(fs::exists(again / "models" / "option.ply"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "pmvs" / "models" / "option.ply"));
  // Both runs are listed among the commands that repeat the benchmark.
  EXPECT_NE(markdown.find(stand_in_.string() + " " + (dir_ / "out" / "pmvs").string() + "/ option"),
            std::string::npos)
      << markdown;
  EXPECT_NE(markdown.find(again.string() + "/ option"), std::string::npos) << markdown;
}

TEST_F(VersusPmvs2Test, RunsOpenMvsOnAColmapFolderAsASecondAnchor) {
  // A COLMAP folder as sapmvs exports it, in a local frame: the cloud comes
  // back to the world frame through the export's side file, as PMVS2's does.
  const fs::path colmap = dir_ / "colmap";
  const test::CliResult e = test::RunCli("export " + block_.string() + " --format colmap --out " +
                                         colmap.string() + " -q");
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const fs::path bin = dir_ / "openmvs";
  fs::create_directories(bin);
  std::ofstream(bin / "InterfaceCOLMAP") << kStandInInterfaceColmap;
  std::ofstream(bin / "DensifyPointCloud") << kStandInDensify;
  for (const char* name : {"InterfaceCOLMAP", "DensifyPointCloud"}) {
    fs::permissions(bin / name, fs::perms::owner_all, fs::perm_options::add);
  }
  block_ = colmap;
  const fs::path md = dir_ / "table.md";
  const test::CliResult r = Versus("--modes sapmvs --openmvs --openmvs-bin " + bin.string() +
                                   " --markdown " + md.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string markdown = test::Slurp(md);
  const std::vector<std::string> openmvs = Row(markdown, "OpenMVS DensifyPointCloud");
  const std::vector<std::string> first = Row(markdown, "PMVS2");
  ASSERT_FALSE(first.empty()) << markdown;
  ASSERT_EQ(openmvs.size(), first.size()) << markdown;
  EXPECT_NE(openmvs[1], "–") << "DensifyPointCloud is timed";
  EXPECT_EQ(openmvs[9], "4");
  EXPECT_EQ(openmvs[10], "100.0 %") << markdown;
  EXPECT_EQ(openmvs[12], "100.0 %") << markdown;
  // In the second table, beside PMVS2 and sapmvs.
  const std::string surface = markdown.substr(markdown.find("| tool / mode | points |"));
  EXPECT_FALSE(Row(surface, "OpenMVS DensifyPointCloud").empty()) << surface;
  EXPECT_NE(markdown.find((bin / "InterfaceCOLMAP").string() + " -i " + colmap.string()),
            std::string::npos)
      << markdown;
}

TEST_F(VersusPmvs2Test, RefusesOpenMvsOnAFolderItCannotRead) {
  // The simulated block is a block.yaml, not COLMAP's undistorted folder.
  const test::CliResult r = Versus("--openmvs --openmvs-bin " + dir_.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("COLMAP's undistorted folder"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "refused before any work";
}

TEST_F(VersusPmvs2Test, AFailingPmvs2EndsTheBenchmarkNamingItsLog) {
  // --threads 2 puts "CPU 2" in the option file, which the stand-in refuses.
  const test::CliResult r = Versus("--modes sapmvs", 2);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("pmvs2.log"), std::string::npos) << r.err;
  EXPECT_EQ(test::CountLines(r.err.substr(r.err.find("versus_pmvs2:"))), 1) << r.err;
  const std::string log = test::Slurp(dir_ / "out" / "logs" / "pmvs2.log");
  EXPECT_NE(log.find("without CPU 1"), std::string::npos) << log;
}

TEST_F(VersusPmvs2Test, RefusesASecondPmvs2RunOfAnEarlierCloud) {
  const fs::path cloud = dir_ / "earlier.ply";
  std::ofstream(cloud) << "ply\n";
  const test::CliResult r = Versus("--pmvs2-again --pmvs2-cloud " + cloud.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--pmvs2-again"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "refused before any work";
}

}  // namespace
}  // namespace sapmvs

// `sapmvs run` and `simulate` and their output folders: a folder sapmvs did
// not make is refused, a busy one too, a failed start leaves nothing behind,
// and a full disk fails in one line with the earlier files intact and a
// resume that works. Each message is compared whole (docs/bad-inputs.md).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_test_util.h"
#include "device/cl_devices.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/output_folder.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::RunCli;

bool HavePrlimit() { return std::system("prlimit --version >/dev/null 2>&1") == 0; }

// RunCli's prefix for a command whose files may not grow past `bytes`: a
// full disk, as EFBIG ("File too large") instead of ENOSPC. For commands
// without OpenCL only: the PoCL driver writes large temporary files.
std::string FileSizeLimit(long bytes) {
  return "trap '' XFSZ; prlimit --fsize=" + std::to_string(bytes);
}

// RunCli's prefix for a command whose files under `dir` cannot grow past
// `bytes` (full_disk_preload.cc): ENOSPC there, nowhere else.
std::string FullDiskUnder(const fs::path& dir, long bytes) {
  return std::string("LD_PRELOAD=") + SAPMVS_FULL_DISK_PRELOAD +
         " SAPMVS_FULL_DISK_DIR=" + dir.string() +
         " SAPMVS_FULL_DISK_BYTES=" + std::to_string(bytes);
}

using test::Slurp;

void Spit(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary) << text;
}

// Empty files and AtomicFile temporaries under `dir`: what a failed write
// must not leave.
std::string EmptyOrTempFiles(const fs::path& dir) {
  std::string found;
  if (!fs::exists(dir)) return found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    if (fs::file_size(e.path()) == 0 || name.find(".tmp.") != std::string::npos) {
      found += e.path().string() + " ";
    }
  }
  return found;
}

class CliOutputTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() /
                         ("sapmvs_cli_output_test_" + std::to_string(::getpid())));
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

  // The tiny block at half scale (seconds), simulated on first use only
  // (most tests here are refused before any block is read) and shared by
  // the test processes: read only.
  static fs::path Block() { return test::Simulated("tiny", 1, 0.5) / "block.yaml"; }
  static fs::path NoBlock() { return *root_ / "no_block" / "block.yaml"; }
  // Two groups (one per strip), each matched in 2 images.
  static std::string Run(const fs::path& block, const fs::path& out, const std::string& more = "") {
    return "run " + block.string() + " --out " + out.string() +
           " --min-image-num 2 --max-images 3 -q " + more;
  }
  bool NoOutput() const { return !fs::exists(out_) || fs::is_empty(out_); }

  static fs::path* root_;
  fs::path out_;
};

fs::path* CliOutputTest::root_ = nullptr;

TEST_F(CliOutputTest, RunRefusesAFolderItDidNotMake) {
  Spit(out_ / "cloud.ply", "the user's own cloud");
  const auto r = RunCli(Run(NoBlock(), out_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: " + out_.string() +
                       ": folder is not empty and was not written by sapmvs run (no "
                       ".sapmvs_run); give a new or empty folder\n");
  EXPECT_EQ(Slurp(out_ / "cloud.ply"), "the user's own cloud");
  EXPECT_FALSE(fs::exists(out_ / ".sapmvs_run"));
}

TEST_F(CliOutputTest, RunRefusesAnOutputThatIsAFile) {
  Spit(out_, "a file");
  const auto r = RunCli(Run(NoBlock(), out_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err,
            "sapmvs: " + out_.string() + ": exists and is not a folder; give a folder for --out\n");
  EXPECT_EQ(Slurp(out_), "a file");
}

TEST_F(CliOutputTest, SimulateRefusesAFolderItDidNotMake) {
  Spit(out_ / "block.yaml", "the user's own block");
  const auto r = RunCli("simulate --preset tiny --out " + out_.string() + " -q");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: " + out_.string() +
                       ": folder is not empty and was not written by sapmvs simulate (no "
                       ".sapmvs_simulate); give a new or empty folder\n");
  EXPECT_EQ(Slurp(out_ / "block.yaml"), "the user's own block");
  EXPECT_FALSE(fs::exists(out_ / "images"));
}

// This process holds the folder's lock as a running `sapmvs run` would; a
// second run and a --restart are refused naming it and delete nothing.
TEST_F(CliOutputTest, RunOnABusyFolderIsRefusedNamingThePid) {
  const OutputFolder busy(out_, "run");
  Spit(out_ / "groups" / "group_001.json", "{\"status\": \"done\"}");
  const std::string expected = "sapmvs: " + out_.string() + ": in use by another sapmvs run (pid " +
                               std::to_string(::getpid()) +
                               "); wait for it to finish or give another --out\n";
  const auto r = RunCli(Run(NoBlock(), out_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, expected);
  const auto restart = RunCli(Run(NoBlock(), out_, "--restart"));
  EXPECT_EQ(restart.exit_code, 1);
  EXPECT_EQ(restart.err, expected);
  EXPECT_TRUE(fs::exists(out_ / "groups" / "group_001.json"));
}

// A failed start writes nothing, so the corrected command is not refused
// (before, groups/plan.json stayed and asked for --restart).
TEST_F(CliOutputTest, BadDeviceLeavesNothingBehind) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli(Run(Block(), out_, "--device 99"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err.rfind("sapmvs: OpenCL device index 99 (from --device) is out of range; "
                        "available: 0: ",
                        0),
            0u)
      << r.err;
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_TRUE(NoOutput());
}

TEST_F(CliOutputTest, NoOpenClPlatformLeavesNothingBehind) {
  const auto r = RunCli(Run(Block(), out_), "OCL_ICD_VENDORS=/tmp/none");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err,
            "sapmvs: no OpenCL platform found; install one, e.g. `sudo apt-get install "
            "pocl-opencl-icd` (CPU) or your GPU vendor's OpenCL driver\n");
  EXPECT_TRUE(NoOutput());
}

// The CRS is needed only by cloud.las and dsm.tif, written after all the
// matching; it is checked before any.
TEST_F(CliOutputTest, InvalidCrsIsRefusedBeforeAnyWork) {
  const fs::path block = *root_ / "bad_crs.yaml";  // the shared block stays as it is
  std::string yaml = Slurp(Block());
  const auto set = [&](const std::string& key, const std::string& value) {
    const size_t at = yaml.find(key);
    ASSERT_NE(at, std::string::npos) << yaml;
    yaml.replace(at, yaml.find('\n', at) - at, key + value);
  };
  set("crs: ", "\"hello\"");
  set("images: ", (Block().parent_path() / "images").string());
  set("file: ", (Block().parent_path() / "orientation.txt").string());
  set("dem: ", (Block().parent_path() / "truth" / "dsm.tif").string());
  Spit(block, yaml);
  const auto r = RunCli(Run(block, out_), "OCL_ICD_VENDORS=/tmp/none");
  EXPECT_EQ(r.exit_code, 1);  // before the device is looked for
  EXPECT_EQ(r.err,
            "sapmvs: " + block.string() + ": CRS 'hello': expected WKT, EPSG:n or a PROJ string\n");
  EXPECT_TRUE(NoOutput());
}

// The DSM rasters need the GDAL module (cli/gdal_module.h), which the binary
// loads only then: a binary without it refuses the run before any work, as
// it refuses a bad CRS.
TEST_F(CliOutputTest, MissingGdalModuleIsRefusedBeforeAnyWork) {
  const fs::path bin = *root_ / "bin_without_module";
  fs::create_directories(bin);
  std::error_code ec;
  fs::create_hard_link(test::CliPath(), bin / "sapmvs", ec);
  if (ec) fs::copy_file(test::CliPath(), bin / "sapmvs");
  ASSERT_FALSE(fs::exists(bin / "libsapmvs_gdal.so"));
  const auto r = test::RunCommand((bin / "sapmvs").string() + " " + Run(Block(), out_));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: libsapmvs_gdal.so: cannot load the GDAL module (" +
                       (bin / "libsapmvs_gdal.so").string() + " and " +
                       (*root_ / "lib" / "sapmvs" / "libsapmvs_gdal.so").string() +
                       " missing; expected it beside the sapmvs binary or in ../lib/sapmvs)\n");
  EXPECT_TRUE(NoOutput());
}

TEST_F(CliOutputTest, MissingProfileFolderIsRefusedBeforeAnyWork) {
  const fs::path csv = *root_ / "no_such_folder" / "profile.csv";
  const auto r = RunCli(Run(NoBlock(), out_, "--profile " + csv.string()));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: --profile " + csv.string() + ": cannot write, directory " +
                       csv.parent_path().string() + " does not exist\n");
  EXPECT_TRUE(NoOutput());
}

// A full disk while a group's checkpoint is written: one line naming it, the
// plan kept whole, no empty or cut file; a temporary file of a run killed
// meanwhile is cleaned up by the resume, which needs no --restart.
TEST_F(CliOutputTest, FullDiskAtACheckpointKeepsThePlanAndResumes) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli(Run(Block(), out_), FullDiskUnder(out_, 4096));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: " + (out_ / "groups" / "group_001.ply").string() +
                       ": write failed: No space left on device\n");
  EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
  EXPECT_EQ(EmptyOrTempFiles(out_), "");
  EXPECT_NO_THROW(nlohmann::json::parse(Slurp(out_ / "groups" / "plan.json")));
  EXPECT_FALSE(fs::exists(out_ / "groups" / "group_001.json"));

  const pid_t child = ::fork();  // a pid that no longer runs
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);
  const std::string killed = ".tmp." + std::to_string(child) + ".0";
  Spit(out_ / (".cloud.ply" + killed), "cut");
  Spit(out_ / "groups" / (".group_002.ply" + killed), "cut");

  const auto resumed = RunCli(Run(Block(), out_));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
  EXPECT_TRUE(fs::exists(out_ / "cloud.ply"));
  EXPECT_EQ(EmptyOrTempFiles(out_), "");
}

// A full disk at the final cloud: the groups' checkpoints stay, the resume
// matches nothing again and writes the bytes an undisturbed run writes; then
// --restart deletes what sapmvs wrote and nothing else.
TEST_F(CliOutputTest, FullDiskAtTheCloudKeepsTheGroupsAndResumesToTheSameBytes) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const fs::path cut = out_ / "cut";
  // Undisturbed: the run of Run(), shared (read only).
  const auto [whole, a] = test::SharedRun(Block(), "--min-image-num 2 --max-images 3 -q");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const uintmax_t group_max = std::max(fs::file_size(whole / "groups" / "group_001.ply"),
                                       fs::file_size(whole / "groups" / "group_002.ply"));
  const uintmax_t cloud = fs::file_size(whole / "cloud.ply");
  ASSERT_GT(cloud, group_max + 2);  // the merged cloud is the largest file

  const auto b = RunCli(Run(Block(), cut), FullDiskUnder(cut, (group_max + cloud) / 2));
  EXPECT_EQ(b.exit_code, 1);
  // The cloud's and the DSM's writers run side by side: the one that meets
  // the full disk first names its file, in one line, and leaves none of it.
  std::string named;
  for (const char* f : {"cloud.ply", "cloud.las", "dsm.tif", "dsm_color.tif", "dsm.png"}) {
    if (b.err == "sapmvs: " + (cut / f).string() + ": write failed: No space left on device\n") {
      named = f;
    }
  }
  ASSERT_FALSE(named.empty()) << b.err;
  EXPECT_EQ(b.out.find("wrote"), std::string::npos) << b.out;
  EXPECT_EQ(EmptyOrTempFiles(cut), "");
  EXPECT_FALSE(fs::exists(cut / named));
  EXPECT_TRUE(fs::exists(cut / "groups" / "group_002.json"));

  const auto c = RunCli(Run(Block(), cut));
  ASSERT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.out.find("(checkpoint)"), std::string::npos) << c.out;
  EXPECT_TRUE(Slurp(cut / "cloud.ply") == Slurp(whole / "cloud.ply")) << "resumed cloud differs";

  Spit(cut / "notes.txt", "mine");
  Spit(cut / "groups" / "notes.txt", "mine too");
  const auto d = RunCli(Run(Block(), cut, "--restart"));
  ASSERT_EQ(d.exit_code, 0) << d.err;
  EXPECT_EQ(d.out.find("(checkpoint)"), std::string::npos) << d.out;
  EXPECT_EQ(Slurp(cut / "notes.txt"), "mine");
  EXPECT_EQ(Slurp(cut / "groups" / "notes.txt"), "mine too");
}

// simulate on a full disk: one line naming the first file that did not fit,
// no empty or cut file; the folder is sapmvs's, so a rerun fills it.
TEST_F(CliOutputTest, SimulateOnAFullDiskLeavesNoCutFile) {
  if (!HavePrlimit()) GTEST_SKIP() << "prlimit missing (util-linux)";
  const std::string args = "simulate --preset tiny --scale 0.5 --out " + out_.string() + " -q";
  const auto r = RunCli(args, FileSizeLimit(1024));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "sapmvs: " + (out_ / "images" / "IMG_0001.png").string() +
                       ": write failed: File too large\n");
  EXPECT_EQ(EmptyOrTempFiles(out_), "");
  EXPECT_FALSE(fs::exists(out_ / "block.yaml"));
  const auto again = RunCli(args);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_TRUE(fs::exists(out_ / "block.yaml"));
  EXPECT_EQ(EmptyOrTempFiles(out_), "");
}

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test_util.h"
#include "export_test_block.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::CountLines;
using test::RunCli;

class CliExportTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    block_ = test::WriteDistortedBlock(dir_ / "src");
    out_ = dir_ / "out";
  }
  test::CliResult Export(const std::string& flags) {
    return RunCli("export " + block_.string() + " --out " + out_.string() + " " + flags);
  }
  fs::path block_, out_;
};

TEST_F(CliExportTest, WritesAPmvsFolderQuietlyThatReadsBack) {
  const auto r = Export("--format pmvs -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  EXPECT_NE(r.out.find("pmvs2 " + out_.string() + "/ option"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::is_regular_file(out_ / "sapmvs_frame.json"));
  const auto info = RunCli("info " + out_.string());
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("(pmvs)"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("CRS EPSG:32632"), std::string::npos) << info.out;
}

TEST_F(CliExportTest, WritesAColmapProjectAtALevel) {
  const auto r = Export("--format colmap --level 1 --input-format yaml -q");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("3 images, 1 camera(s), 0 sparse points"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::is_regular_file(out_ / "sparse/0/cameras.txt"));
  EXPECT_TRUE(fs::is_regular_file(out_ / "images/b.jpg"));
  const auto info = RunCli("info " + out_.string());
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("81x61"), std::string::npos) << info.out;  // 161x121 at level 1
}

TEST_F(CliExportTest, ReexportOntoItsOwnFolderWorks) {
  ASSERT_EQ(Export("--format pmvs -q").exit_code, 0);
  const auto r = Export("--format colmap -q");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(fs::exists(out_ / "txt"));
}

TEST_F(CliExportTest, UnknownFormatIsOneLineAndWritesNothing) {
  const auto r = Export("--format ply");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("unknown export format 'ply'"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out_));
}

TEST_F(CliExportTest, ForeignFolderIsRefusedInOneLine) {
  fs::create_directories(out_);
  std::ofstream(out_ / "keep.txt") << "x";
  const auto r = Export("--format colmap");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("sapmvs: " + out_.string() + ": ", 0), 0u) << r.err;
  EXPECT_EQ(std::distance(fs::directory_iterator(out_), fs::directory_iterator()), 1);
}

TEST_F(CliExportTest, BadLevelAndInputFormatAreOneLine) {
  for (const char* flags : {"--format colmap --level 9", "--format pmvs --input-format nope"}) {
    const auto r = Export(flags);
    EXPECT_EQ(r.exit_code, 1) << flags;
    EXPECT_EQ(CountLines(r.err), 1) << flags << ": " << r.err;
    EXPECT_FALSE(fs::exists(out_)) << flags;
  }
}

}  // namespace
}  // namespace sapmvs

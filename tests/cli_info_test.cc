#include <gtest/gtest.h>

#include <fstream>
#include <regex>

#include "cli_test_util.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::RunCli;

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

TEST(CliInfo, NgiBlock) {
  SAPMVS_REQUIRE_PATH(test::SharedDir() / "datasets/orthority_ngi_odm/ngi");
  const auto r = RunCli("info " + (test::TestDir() / "blocks" / "ngi.yaml").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("images         4\n"), std::string::npos) << r.out;
  EXPECT_EQ(Count(r.out, "640x1152"), 5) << r.out;  // camera line + 4 images
  EXPECT_NE(r.out.find("surface from   DEM"), std::string::npos) << r.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex(R"(GSD\s+([0-9.]+) \.\. ([0-9.]+))")))
      << r.out;
  EXPECT_GT(std::stod(m[1]), 5.5);
  EXPECT_LT(std::stod(m[2]), 6.2);
  EXPECT_NE(r.out.find("flying height"), std::string::npos);
  EXPECT_NE(r.out.find("ground extent"), std::string::npos);
  EXPECT_NE(r.out.find("local origin   X -56392.000"), std::string::npos) << r.out;
}

TEST(CliInfo, HerzJesu) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const auto r = RunCli("info " + test::HerzJesu().string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("images         8\n"), std::string::npos) << r.out;
  EXPECT_EQ(Count(r.out, "3072x2048"), 9) << r.out;
  EXPECT_NE(r.out.find("(strecha)"), std::string::npos);
}

TEST(CliInfo, GroundHeightFlagFillsAMissingSurface) {
  SAPMVS_REQUIRE_PATH(test::SharedDir() / "datasets/orthority_ngi_odm/odm/opensfm");
  const std::string json =
      (test::SharedDir() / "datasets/orthority_ngi_odm/odm/opensfm/reconstruction.json").string();
  const auto without = RunCli("info " + json);
  ASSERT_EQ(without.exit_code, 0) << without.err;
  EXPECT_NE(without.out.find("GSD            unknown"), std::string::npos) << without.out;
  const auto with = RunCli("info --ground-height 98 " + json);
  ASSERT_EQ(with.exit_code, 0) << with.err;
  EXPECT_NE(with.out.find("surface from   ground height (Z = 98.000)"), std::string::npos)
      << with.out;
}

TEST(CliInfo, MissingBlockIsOneLineAndExitCode1) {
  const auto r = RunCli("info /nonexistent/block.yaml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("/nonexistent/block.yaml"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST(CliInfo, MalformedBlockNamesFileAndLine) {
  const auto dir = test::ScratchDir();
  std::ofstream(dir / "block.yaml")
      << "camera:\n  width: 640\n  height: 480\n  focal_mm: 35\n  pixel_um: 5\n"
      << "images: .\norientation:\n  file: o.txt\n  angles: opk\n  units: degrees\n";
  std::ofstream(dir / "o.txt") << "# name X Y Z o p k\nimg 1 2 3 4 5\n";
  const auto r = RunCli("info " + (dir / "block.yaml").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("o.txt:2: expected 7 fields"), std::string::npos) << r.err;
}

TEST(CliInfo, UnknownFormatIsRejected) {
  const auto r = RunCli("info --format bundler .");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown block format 'bundler'"), std::string::npos) << r.err;
}

TEST(Cli, HelpListsOnlyWorkingSubcommands) {
  const auto r = RunCli("--help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("devices"), std::string::npos);
  EXPECT_NE(r.out.find("info"), std::string::npos);
  EXPECT_NE(r.out.find("simulate"), std::string::npos);
  EXPECT_NE(r.out.find("evaluate"), std::string::npos);
  EXPECT_NE(r.out.find("run"), std::string::npos);
  EXPECT_NE(r.out.find("  plan "), std::string::npos) << r.out;
}

}  // namespace
}  // namespace sapmvs

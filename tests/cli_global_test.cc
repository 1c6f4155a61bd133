// Exit codes and the global flags (-v, --threads, --log), through the built
// binary as a user runs it. None of these needs an OpenCL device.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "cli_test_util.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::CountLines;
using test::RunCli;
using test::RunCommand;

// One line on stderr that begins "sapmvs: " and contains each of `names`,
// exit code 1, nothing on stdout.
void ExpectOneLineError(const test::CliResult& r, const std::vector<std::string>& names) {
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(CountLines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("sapmvs: ", 0), 0u) << r.err;
  for (const std::string& n : names) EXPECT_NE(r.err.find(n), std::string::npos) << r.err;
  EXPECT_EQ(r.out, "");
}

TEST(CliExitCodes, NonIntegerLevelIsOneLineAndExitCode1) {
  const auto r = RunCli("run /tmp/x --level abc");
  ExpectOneLineError(r, {"--level", "'abc'", "integer", "sapmvs run --help"});
}

TEST(CliExitCodes, NonNumericValueOfAFloatOptionNamesIt) {
  const auto r = RunCli("run /tmp/x --out /tmp/y --threshold high");
  ExpectOneLineError(r, {"--threshold", "'high'", "a number"});
}

TEST(CliExitCodes, UnknownFlagIsOneLineAndExitCode1) {
  const auto r = RunCli("info /tmp/x --no-such-flag");
  ExpectOneLineError(r, {"unknown option", "--no-such-flag", "sapmvs info --help"});
}

TEST(CliExitCodes, MissingSubcommandIsOneLineAndExitCode1) {
  for (const std::string args : {"", "-q", "--threads 2"}) {
    SCOPED_TRACE(args);
    ExpectOneLineError(RunCli(args), {"subcommand", "run", "sapmvs --help"});
  }
}

TEST(CliExitCodes, UnknownSubcommandIsNamed) {
  ExpectOneLineError(RunCli("frobnicate"), {"unknown subcommand 'frobnicate'", "run"});
  ExpectOneLineError(RunCli("-q frobnicate --out x"), {"unknown subcommand 'frobnicate'"});
}

TEST(CliExitCodes, ExtraPositionalIsOneLineAndExitCode1) {
  ExpectOneLineError(RunCli("info /tmp/a /tmp/b"), {"unexpected argument", "/tmp/b"});
}

TEST(CliExitCodes, MissingRequiredOptionIsNamed) {
  ExpectOneLineError(RunCli("run /tmp/x"), {"missing option --out"});
  ExpectOneLineError(RunCli("evaluate"), {"missing argument CLOUD"});
  ExpectOneLineError(RunCli("run /tmp/x --out"), {"--out"});
}

TEST(CliExitCodes, HelpAndVersionExit0OnStdout) {
  for (const std::string args : {"--help", "run --help", "--version"}) {
    SCOPED_TRACE(args);
    const auto r = RunCli(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "");
    EXPECT_FALSE(r.out.empty());
  }
  const auto v = RunCli("--version");
  EXPECT_EQ(v.out.rfind(std::string("sapmvs ") + SAPMVS_VERSION + " (commit ", 0), 0u) << v.out;
  const auto h = RunCli("--help");
  for (const std::string flag : {"--threads", "--verbose", "--log", "--quiet"}) {
    EXPECT_NE(h.out.find(flag), std::string::npos) << h.out;
  }
}

// Built from a git checkout of its own, --version names a commit of that
// checkout ("unknown" is for a tarball or a copy inside another repository).
TEST(CliExitCodes, VersionNamesTheCommitOfItsCheckout) {
  const std::filesystem::path source = std::filesystem::weakly_canonical(test::TestDir() / "..");
  const std::string git = "git -C '" + source.string() + "' ";
  std::string top = RunCommand(git + "rev-parse --show-toplevel").out;
  while (!top.empty() && top.back() == '\n') top.pop_back();
  if (top.empty() || std::filesystem::weakly_canonical(top) != source) {
    GTEST_SKIP() << source << " is not the top of a git checkout";
  }
  const auto v = RunCli("--version");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(v.out, m, std::regex(R"(\(commit ([0-9a-f]{7,40})\))"))) << v.out;
  EXPECT_EQ(RunCommand(git + "cat-file -e " + m[1].str() + "^{commit}").exit_code, 0) << m[1];
}

TEST(CliGlobalFlags, BadThreadCountIsOneLineNamingIt) {
  ExpectOneLineError(RunCli("--threads -1 info /tmp/x"), {"--threads", "-1"});
  ExpectOneLineError(RunCli("info /tmp/x --threads 1.5"), {"--threads", "'1.5'", "integer"});
  ExpectOneLineError(RunCli("info /tmp/x --threads many"), {"--threads", "'many'"});
}

using test::Slurp;

class CliLogTest : public test::ScratchTest {
 protected:
  // Half scale, as cli_output's: the quickest simulated block (shared).
  static fs::path Block() { return test::Simulated("tiny", 1, 0.5) / "block.yaml"; }
};

// Refused in one line before the subcommand does anything: no output, and
// nothing created.
TEST_F(CliLogTest, LogThatCannotBeOpenedIsRefusedBeforeAnyWork) {
  const fs::path missing = dir_ / "no" / "such" / "run.log";
  ExpectOneLineError(RunCli("info " + Block().string() + " --log " + missing.string()),
                     {"--log", missing.string()});
  EXPECT_FALSE(fs::exists(missing.parent_path()));
  ExpectOneLineError(RunCli("--log " + dir_.string() + " info " + Block().string()),
                     {"--log", dir_.string()});
}

// Every line the commands print, their exit codes and their command lines,
// with timestamps, appended run after run; the console output is unchanged.
TEST_F(CliLogTest, LogAppendsEverythingPrintedWithTimestamps) {
  const fs::path log = dir_ / "sapmvs.log";
  const auto plain = RunCli("info " + Block().string());
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto logged = RunCli("info " + Block().string() + " --log " + log.string());
  ASSERT_EQ(logged.exit_code, 0) << logged.err;
  EXPECT_EQ(logged.out, plain.out);
  EXPECT_EQ(logged.err, "");
  const auto failed = RunCli("--log " + log.string() + " info " + (dir_ / "none.yaml").string());
  ASSERT_EQ(failed.exit_code, 1);
  EXPECT_EQ(CountLines(failed.err), 1) << failed.err;

  const std::string text = Slurp(log);
  const std::regex stamped(
      R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z (start |exit  |stdout|stderr|detail) .*)");
  std::istringstream lines(text);
  std::string line;
  std::vector<std::string> starts, exits, out, err;
  while (std::getline(lines, line)) {
    ASSERT_TRUE(std::regex_match(line, stamped)) << line;
    const std::string kind = line.substr(25, 6), rest = line.substr(32);
    if (kind == "start ") starts.push_back(rest);
    if (kind == "exit  ") exits.push_back(rest);
    if (kind == "stdout") out.push_back(rest);
    if (kind == "stderr") err.push_back(rest);
  }
  ASSERT_EQ(starts.size(), 2u) << text;
  EXPECT_NE(starts[0].find(" info " + Block().string() + " --log " + log.string()),
            std::string::npos)
      << starts[0];
  EXPECT_EQ(exits, (std::vector<std::string>{"0", "1"})) << text;
  // info's stdout, line for line (blank lines are not logged).
  std::istringstream printed(plain.out);
  std::vector<std::string> want;
  while (std::getline(printed, line)) {
    if (!line.empty()) want.push_back(line);
  }
  EXPECT_EQ(out, want);
  ASSERT_EQ(err.size(), 1u) << text;
  EXPECT_EQ(err[0] + "\n", failed.err);
}

}  // namespace
}  // namespace sapmvs

#pragma once
// Runs the built `sapmvs` binary as a user would and captures what it prints.

#include <filesystem>
#include <string>

#include "test_util.h"

namespace sapmvs::test {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs a shell command line, stdin from /dev/null, capturing stdout and
// stderr.
CliResult RunCommand(const std::string& command);

// The built `sapmvs` binary.
std::filesystem::path CliPath();

// Runs `env sapmvs args` through the shell; `env` is a prefix such as
// "OCL_ICD_VENDORS=/tmp/none" (may be empty).
CliResult RunCli(const std::string& args, const std::string& env = "");

// `sapmvs run BLOCK --out OUT ARGS`, run once for every test process of this
// build (a SharedFolder): for the tests that only read what a run printed and
// wrote. Read only: a test writes its own files elsewhere.
struct SharedRunResult {
  std::filesystem::path out;  // the run's --out
  CliResult result;
};
SharedRunResult SharedRun(const std::filesystem::path& block, const std::string& args);

int CountLines(const std::string& text);

// Whether an OpenCL device is there for the CLI's matching to run on.
bool HaveOpenClDevice();

}  // namespace sapmvs::test

// Skips (or, with SAPMVS_REQUIRE_OPENCL=1, fails) a test that needs an OpenCL
// device when there is none.
#define SAPMVS_REQUIRE_OPENCL_DEVICE()                                \
  do {                                                                \
    if (!::sapmvs::test::HaveOpenClDevice())                          \
      SAPMVS_SKIP_WITHOUT_OPENCL("no OpenCL device on this machine"); \
  } while (0)

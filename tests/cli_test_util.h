#pragma once
// Runs the built `sapmvs` binary as a user would and captures what it prints.

#include <string>

namespace sapmvs::test {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `env sapmvs args` through the shell; `env` is a prefix such as
// "OCL_ICD_VENDORS=/tmp/none" (may be empty).
CliResult RunCli(const std::string& args, const std::string& env = "");

int CountLines(const std::string& text);

// Whether an OpenCL device is there for the CLI's matching to run on.
bool HaveOpenClDevice();

}  // namespace sapmvs::test

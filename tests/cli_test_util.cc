#include "cli_test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "device/cl_devices.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs::test {

CliResult RunCommand(const std::string& command) {
  // Not ScratchDir(): that would wipe the calling test's own files.
  static int calls = 0;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("sapmvs_cli_" + std::to_string(::getpid()) + "_" + std::to_string(++calls));
  std::filesystem::create_directories(dir);
  const std::string cmd = command + " > " + (dir / "out.txt").string() + " 2> " +
                          (dir / "err.txt").string() + " < /dev/null";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = Slurp(dir / "out.txt");
  r.err = Slurp(dir / "err.txt");
  std::filesystem::remove_all(dir);
  return r;
}

std::filesystem::path CliPath() { return SAPMVS_CLI_PATH; }

CliResult RunCli(const std::string& args, const std::string& env) {
  return RunCommand(env + (env.empty() ? "" : " ") + SAPMVS_CLI_PATH + " " + args);
}

SharedRunResult SharedRun(const std::filesystem::path& block, const std::string& args) {
  const std::string id =
      "run_" + std::to_string(std::hash<std::string>{}(block.string() + " " + args));
  const std::filesystem::path dir = SharedFolder(id, [&](const std::filesystem::path& d) {
    std::filesystem::create_directories(d);
    const CliResult r =
        RunCli("run " + block.string() + " --out " + (d / "out").string() + " " + args);
    std::ofstream(d / "exit_code") << r.exit_code;
    std::ofstream(d / "stdout", std::ios::binary) << r.out;
    std::ofstream(d / "stderr", std::ios::binary) << r.err;
  });
  SharedRunResult s;
  s.out = dir / "out";
  std::ifstream(dir / "exit_code") >> s.result.exit_code;
  s.result.out = Slurp(dir / "stdout");
  s.result.err = Slurp(dir / "stderr");
  return s;
}

int CountLines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  if (!text.empty() && text.back() != '\n') ++n;
  return n;
}

bool HaveOpenClDevice() {
  try {
    return !ListDevices().empty();
  } catch (const Error&) {
    return false;
  }
}

}  // namespace sapmvs::test

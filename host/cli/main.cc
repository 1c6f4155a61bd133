// The `sapmvs` command line. Only subcommands that work are registered.
//
// Exit codes: 0 success (and --help, --version); 1 bad input, bad flags
// included; 2 no OpenCL platform or device (sapmvs/error.h). Every failure is
// one line on stderr that begins "sapmvs: ".

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

#include "cli/cli.h"
#include "cli/gdal_module.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/log.h"
#include "sapmvs/util/memory_use.h"
#include "util/build_info.h"

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == sapmvs::kCheckCrsArgument) {
    return sapmvs::CheckCrsMain(argv[2]);
  }
  sapmvs::ReturnLargeBlocksToSystem();
  CLI::App app{"sapmvs: dense image matching (IG-SAPMVS) for UAV and aerial blocks on OpenCL"};
  app.set_version_flag("--version", std::string("sapmvs ") + sapmvs::BuildVersion() + " (commit " +
                                        sapmvs::BuildCommit() + ")");
  app.require_subcommand(1);
  // Global flags such as --quiet may also follow the subcommand.
  app.fallthrough();
  sapmvs::cli::GlobalFlags global;
  global.command_line.assign(argv, argv + argc);
  sapmvs::cli::AddGlobalFlags(app, &global);
  // Runs after the whole command line is parsed and checked, before the
  // subcommand's callback does any work.
  app.parse_complete_callback([&global] { sapmvs::cli::ApplyGlobalFlags(global); });

  sapmvs::cli::RegisterDevicesCommand(app, global);
  sapmvs::cli::RegisterInfoCommand(app, global);
  sapmvs::cli::RegisterSimulateCommand(app, global);
  sapmvs::cli::RegisterRunCommand(app, global);
  sapmvs::cli::RegisterPlanCommand(app, global);
  sapmvs::cli::RegisterEvaluateCommand(app, global);
  sapmvs::cli::RegisterExportCommand(app, global);
  sapmvs::cli::RegisterReportCommand(app, global);
  sapmvs::cli::RegisterOptionsReferenceCommand(app, global);

  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version arrive as "errors" with exit code 0.
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "sapmvs: " << sapmvs::cli::DescribeParseError(app, e) << "\n";
    code = 1;
  } catch (const sapmvs::Error& e) {
    std::cerr << "sapmvs: " << e.what() << "\n";
    code = e.ExitCode();
  } catch (const std::exception& e) {
    std::cerr << "sapmvs: " << e.what() << "\n";
    code = 1;
  }
  sapmvs::EndLog(code);
  return code;
}

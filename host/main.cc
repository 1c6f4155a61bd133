// The `sapmvs` command line. Only subcommands that work are registered.

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>

#include "cli.h"
#include "sapmvs/error.h"

int main(int argc, char** argv) {
  CLI::App app{"sapmvs: dense image matching (IG-SAPMVS) for UAV and aerial blocks on OpenCL"};
  app.set_version_flag("--version", std::string(SAPMVS_VERSION));
  app.require_subcommand(1);
  // Global flags such as --quiet may also follow the subcommand.
  app.fallthrough();
  sapmvs::cli::GlobalFlags global;
  app.add_flag("-q,--quiet", global.quiet, "No progress output");

  sapmvs::cli::RegisterDevicesCommand(app, global);
  sapmvs::cli::RegisterInfoCommand(app, global);
  sapmvs::cli::RegisterSimulateCommand(app, global);
  sapmvs::cli::RegisterRunCommand(app, global);
  sapmvs::cli::RegisterPlanCommand(app, global);
  sapmvs::cli::RegisterEvaluateCommand(app, global);
  sapmvs::cli::RegisterExportCommand(app, global);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const sapmvs::Error& e) {
    std::cerr << "sapmvs: " << e.what() << "\n";
    return e.ExitCode();
  } catch (const std::exception& e) {
    std::cerr << "sapmvs: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

#pragma once
// Subcommands of the `sapmvs` CLI. Each Register function adds one subcommand
// whose flags map one to one onto the fields of its component's options struct.
// Callbacks throw sapmvs::Error on failure; main() turns that into one line on
// stderr and the error's exit code.

namespace CLI {
class App;
}

namespace sapmvs::cli {

// Global flags shared by all subcommands.
struct GlobalFlags {
  bool quiet = false;  // No progress output, even on a terminal.
};

void RegisterDevicesCommand(CLI::App& app, const GlobalFlags& global);
void RegisterInfoCommand(CLI::App& app, const GlobalFlags& global);
void RegisterSimulateCommand(CLI::App& app, const GlobalFlags& global);
void RegisterEvaluateCommand(CLI::App& app, const GlobalFlags& global);
void RegisterRunCommand(CLI::App& app, const GlobalFlags& global);

}  // namespace sapmvs::cli

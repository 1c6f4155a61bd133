#pragma once
// Subcommands of the `sapmvs` CLI. Each Register function adds one subcommand
// whose flags map one to one onto the fields of its component's options struct.
// Callbacks throw sapmvs::Error on failure; main() turns that into one line on
// stderr and the error's exit code.

#include <limits>
#include <string>

#include "sapmvs/block.h"
#include "sapmvs/block_reader.h"

namespace CLI {
class App;
}

namespace sapmvs::cli {

// Global flags shared by all subcommands.
struct GlobalFlags {
  bool quiet = false;  // No progress output, even on a terminal.
};

// How a subcommand reads its BLOCK argument: --format, --image-dir,
// --no-size-check, --ground-height, the same for every subcommand.
struct BlockFlags {
  std::string format = "auto";
  BlockReadOptions read;
  double ground_height = std::numeric_limits<double>::quiet_NaN();
};
// `format_flag` names the block format's flag: "--input-format" where
// --format names what a subcommand writes (export).
void AddBlockFlags(CLI::App* cmd, BlockFlags* flags, const std::string& format_flag = "--format");
// The flags as BlockReadOptions; throws Error for an unknown format.
BlockReadOptions ReadOptionsOf(const BlockFlags& flags);
// Reads `path` as the flags say; throws Error for a bad flag value.
Block ReadBlockWithFlags(const std::string& path, const BlockFlags& flags);

void RegisterDevicesCommand(CLI::App& app, const GlobalFlags& global);
void RegisterInfoCommand(CLI::App& app, const GlobalFlags& global);
void RegisterSimulateCommand(CLI::App& app, const GlobalFlags& global);
void RegisterEvaluateCommand(CLI::App& app, const GlobalFlags& global);
void RegisterRunCommand(CLI::App& app, const GlobalFlags& global);
void RegisterPlanCommand(CLI::App& app, const GlobalFlags& global);
void RegisterExportCommand(CLI::App& app, const GlobalFlags& global);

}  // namespace sapmvs::cli

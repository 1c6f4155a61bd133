#pragma once
// Subcommands of the `sapmvs` CLI. Each Register function adds one subcommand
// whose flags map one to one onto the fields of its component's options struct.
// Callbacks throw sapmvs::Error on failure; main() turns that into one line on
// stderr and the error's exit code.

#include <limits>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/log.h"

namespace CLI {
class App;
class ParseError;
}  // namespace CLI

namespace sapmvs::cli {

// Global flags shared by all subcommands; they may come before or after the
// subcommand. Applied once (ApplyGlobalFlags) before any subcommand's work.
struct GlobalFlags {
  bool quiet = false;  // -q: no progress output, even on a terminal.
  // --threads: host threads (OpenMP, OpenCV) and PoCL's CPU device; 0 = all
  // cores (thread_count.h).
  int threads = 0;
  LogOptions log;  // -v (verbosity, counted), --log FILE
  // Not a flag: argv as main() got it, for the log and report.json.
  std::vector<std::string> command_line;
};
// Adds -q, -v, --threads and --log to the top-level command.
void AddGlobalFlags(CLI::App& app, GlobalFlags* flags);
// Sets the thread count and starts the log (log.h) with the command line as
// its first line; throws Error for a bad value or a log file that cannot be
// opened. Called once, after parsing and before any subcommand's work.
void ApplyGlobalFlags(const GlobalFlags& flags);

// A CLI11 parse error (unknown flag, bad value, missing subcommand, ...) as
// one line without the "sapmvs: " prefix, naming the flag or value and the
// subcommand's --help.
std::string DescribeParseError(const CLI::App& app, const CLI::ParseError& error);

// How a subcommand reads its BLOCK argument: --format, --image-dir,
// --no-size-check, --ground-height, the same for every subcommand.
struct BlockFlags {
  std::string format = "auto";
  BlockReadOptions read;
  double ground_height = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> enu_origin;  // LAT,LON,H; empty when not given
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
void RegisterReportCommand(CLI::App& app, const GlobalFlags& global);
// Hidden: prints docs/options.md.
void RegisterOptionsReferenceCommand(CLI::App& app, const GlobalFlags& global);

}  // namespace sapmvs::cli

// The flags every subcommand takes: -q, -v, --threads, --log.
#include <CLI/CLI.hpp>

#include <string>

#include "cli/cli.h"
#include "sapmvs/util/log.h"
#include "sapmvs/util/thread_count.h"

namespace sapmvs::cli {
namespace {

// An argument as a shell would need it, so the log's first line can be pasted.
std::string ShellQuoted(const std::string& arg) {
  if (!arg.empty() && arg.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                            "0123456789_-+=.,/:@%") == std::string::npos) {
    return arg;
  }
  std::string out = "'";
  for (const char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

void AddGlobalFlags(CLI::App& app, GlobalFlags* flags) {
  app.add_flag("-q,--quiet", flags->quiet, "No progress output");
  app.add_flag("-v,--verbose", flags->log.verbosity,
               "More detail on stderr: per-stage timings, GDAL's warnings");
  app.add_option("--threads", flags->threads,
                 "Threads on the host and in PoCL's CPU device (0 = all cores; under mpirun, "
                 "`run` divides them among the ranks on one machine)")
      ->capture_default_str();
  app.add_option("--log", flags->log.file,
                 "Append everything printed, and the -v detail, with timestamps to FILE");
}

void ApplyGlobalFlags(const GlobalFlags& flags) {
  // Before the OpenCL platform is loaded: PoCL reads the count only then.
  SetThreadCount(flags.threads);
  std::string line;
  for (const std::string& arg : flags.command_line) {
    line += (line.empty() ? "" : " ") + ShellQuoted(arg);
  }
  StartLog(flags.log, line);
  if (flags.threads > 0) {
    LogDetail("threads: " + std::to_string(flags.threads) + " (host and PoCL's CPU device)");
  }
}

}  // namespace sapmvs::cli

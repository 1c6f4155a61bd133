#pragma once
// Where the tool's messages go. Results are printed on stdout, errors and
// warnings on stderr, as before; `-v` adds detail lines (per-stage timings,
// GDAL's warnings) on stderr. With `--log FILE` every line printed on stdout
// or stderr, and every detail line whatever the verbosity, is also appended to
// FILE with a UTC timestamp, so a run's log is complete even when its console
// was quiet. The progress bar (progress.h) is not a message and is not logged.
//
// The state is process-wide because std::cout and std::cerr are: StartLog()
// once in main(), before any work; EndLog() at exit.

#include <chrono>
#include <filesystem>
#include <string>

namespace sapmvs {

struct LogOptions {
  // 0: results, warnings, errors. 1 (-v): also detail lines on stderr.
  int verbosity = 0;
  // Appended to, with timestamps; empty = no log file.
  std::filesystem::path file;

  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
};

// Applies `options`. With a log file: opens it for appending (throws Error
// naming it when it cannot be), writes a first line with `command_line`, and
// copies std::cout and std::cerr into it from then on.
void StartLog(const LogOptions& options, const std::string& command_line);
// Writes the last line ("exit N") and closes the log file; std::cout and
// std::cerr print only to the console again. Harmless without StartLog().
void EndLog(int exit_code);

// A detail line: on stderr at -v, always in the log file. No trailing newline.
void LogDetail(const std::string& line);
// Whether detail lines are shown on the console (-v).
bool LogVerbose();

// "2024-05-01T12:34:56.789Z": ISO 8601, UTC, milliseconds.
std::string Iso8601Utc(std::chrono::system_clock::time_point t);

}  // namespace sapmvs

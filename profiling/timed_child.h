#pragma once
// A command run as a child process and measured the way `/usr/bin/time -v`
// does, through wait4(): so that programs we did not write (PMVS2) and our
// own are timed alike, each from its own process, threads included.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace sapmvs {

// How often RunTimed samples a command's memory. Reading /proc/PID/status
// reads counters, not the page tables: about 30 us a sample.
constexpr int kMemorySampleMs = 10;

struct ChildCommand {
  std::vector<std::string> argv;  // argv[0]: a path, or a name looked up on PATH
  // Set in the child's environment only (e.g. POCL_CPU_MAX_CU_NUM).
  std::vector<std::pair<std::string, std::string>> env;
  std::filesystem::path log;  // stdout and stderr go here (truncated); empty = inherited

  // The command as a shell line that repeats it, environment first.
  std::string ShellLine() const;
};

struct ChildUsage {
  int exit_code = -1;  // when it exited
  int signal = 0;      // when a signal ended it
  double wall_seconds = 0;
  double cpu_seconds = 0;   // user + system, all its threads and waited-for children
  double peak_rss_mib = 0;  // ru_maxrss
  // What the peak is made of, from /proc/PID/status sampled every
  // kMemorySampleMs while the command runs (its own process, not its
  // children), in the sample of the largest VmRSS; -1 where no sample was
  // taken. A library's pages count in the RSS once mapped and touched,
  // whoever else maps them, and are dropped without a write when memory runs
  // short: the two parts tell what a program loads from what it allocates.
  double files_at_peak_mib = -1;      // RssFile + RssShmem: libraries, mapped files
  double anonymous_at_peak_mib = -1;  // RssAnon: heap, stacks, written library pages
  // Share of the machine's CPU time that its hypervisor gave to other guests
  // while the command ran ("steal" in /proc/stat, all CPUs); -1 where the
  // system does not say. A shared virtual machine's CPU/wall falls with it
  // whatever the program does, so the tables show it beside CPU/wall.
  double host_steal = -1;
  bool Ok() const { return signal == 0 && exit_code == 0; }
  // "exit 3" or "signal 9 (Killed)".
  std::string Describe() const;
};

// Runs and waits. Throws sapmvs::Error when the process cannot be started or
// the log not opened; a failing command is reported in the usage, not thrown.
ChildUsage RunTimed(const ChildCommand& command);

}  // namespace sapmvs

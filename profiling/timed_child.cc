#include "timed_child.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>
#include <utility>

#include "sapmvs/util/error.h"

namespace sapmvs {

namespace {

std::string ShellQuote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789_-+=/.,:@%") == std::string::npos) {
    return s;
  }
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string ChildCommand::ShellLine() const {
  std::ostringstream s;
  for (const auto& [name, value] : env) s << name << "=" << ShellQuote(value) << " ";
  for (size_t i = 0; i < argv.size(); ++i) s << (i ? " " : "") << ShellQuote(argv[i]);
  return s.str();
}

std::string ChildUsage::Describe() const {
  if (signal) return "signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  return "exit " + std::to_string(exit_code);
}

namespace {

// (steal, total) jiffies of all CPUs from /proc/stat's first line; (0, 0)
// where it cannot be read.
std::pair<double, double> StealAndTotalJiffies() {
  std::ifstream f("/proc/stat");
  std::string cpu;
  f >> cpu;
  if (cpu != "cpu") return {0, 0};
  // user nice system idle iowait irq softirq steal (guest times are already
  // in user and nice).
  double field[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (double& v : field) f >> v;
  if (!f) return {0, 0};
  double total = 0;
  for (const double v : field) total += v;
  return {field[7], total};
}

// VmRSS, RssAnon and RssFile + RssShmem of a process, KiB, from
// /proc/PID/status; false once it has exited (a zombie's status has none).
bool ReadMemory(pid_t pid, double* rss, double* anonymous, double* files) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  double value = 0;
  int found = 0;
  *files = 0;
  while (f >> key) {
    if (key == "VmRSS:" && f >> value) {
      *rss = value;
      found |= 1;
    } else if (key == "RssAnon:" && f >> value) {
      *anonymous = value;
      found |= 2;
    } else if ((key == "RssFile:" || key == "RssShmem:") && f >> value) {
      *files += value;
      found |= 4;
    }
    f.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return found == 7;
}

// Samples the memory of `pid` every kMemorySampleMs until stopped.
class MemorySampler {
 public:
  explicit MemorySampler(pid_t pid) : thread_([this, pid] { Run(pid); }) {}
  ~MemorySampler() { Stop(); }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  // Into `u` (after Stop): the parts of the sample of the largest RSS, and
  // that RSS where it is above the peak wait4 gave: a child that resets its
  // own high-water mark (/proc/self/clear_refs, as sapmvs does to measure
  // each group) leaves in ru_maxrss only the peak since its last reset.
  void Report(ChildUsage* u) const {
    if (samples_ == 0) return;
    u->peak_rss_mib = std::max(u->peak_rss_mib, peak_rss_ / 1024);
    u->files_at_peak_mib = files_at_peak_ / 1024;
    u->anonymous_at_peak_mib = anonymous_at_peak_ / 1024;
  }

 private:
  void Run(pid_t pid) {
    while (!stop_) {
      double rss = 0, anonymous = 0, files = 0;
      if (ReadMemory(pid, &rss, &anonymous, &files)) {
        ++samples_;
        if (rss > peak_rss_) {
          peak_rss_ = rss;
          files_at_peak_ = files;
          anonymous_at_peak_ = anonymous;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(kMemorySampleMs));
    }
  }

  std::atomic<bool> stop_{false};
  long samples_ = 0;
  double peak_rss_ = 0, files_at_peak_ = 0, anonymous_at_peak_ = 0;
  std::thread thread_;  // last: starts once the members above are set
};

}  // namespace

ChildUsage RunTimed(const ChildCommand& command) {
  if (command.argv.empty()) throw Error("run: empty command");
  int log_fd = -1;
  if (!command.log.empty()) {
    log_fd = open(command.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (log_fd < 0) throw Error(command.log.string() + ": cannot open: " + strerror(errno));
  }
  std::vector<char*> argv;
  for (const std::string& a : command.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // The exec error travels back through a close-on-exec pipe: an empty read
  // means the exec succeeded.
  int report[2];
  if (pipe2(report, O_CLOEXEC) != 0) throw Error(std::string("pipe: ") + strerror(errno));
  const auto [steal_before, total_before] = StealAndTotalJiffies();
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw Error(std::string("fork: ") + strerror(errno));
  if (pid == 0) {
    close(report[0]);
    for (const auto& [name, value] : command.env) setenv(name.c_str(), value.c_str(), 1);
    if (log_fd >= 0) {
      dup2(log_fd, STDOUT_FILENO);
      dup2(log_fd, STDERR_FILENO);
    }
    execvp(argv[0], argv.data());
    const int e = errno;
    (void)!write(report[1], &e, sizeof e);
    _exit(127);
  }
  close(report[1]);
  if (log_fd >= 0) close(log_fd);
  int exec_errno = 0;
  const bool exec_failed = read(report[0], &exec_errno, sizeof exec_errno) == sizeof exec_errno;
  close(report[0]);
  // The sampler stops once the child has exited but before it is reaped:
  // until then its pid cannot name another process.
  MemorySampler sampler(pid);
  siginfo_t exited{};
  while (waitid(P_PID, pid, &exited, WEXITED | WNOWAIT) < 0) {
    if (errno != EINTR) break;  // wait4 below reports it
  }
  // Before the sampler's last sleep, which would add up to kMemorySampleMs.
  const auto end = std::chrono::steady_clock::now();
  sampler.Stop();
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) throw Error(std::string("wait4: ") + strerror(errno));
  }
  if (exec_failed) throw Error(command.argv[0] + ": cannot run: " + strerror(exec_errno));
  ChildUsage u;
  u.wall_seconds = std::chrono::duration<double>(end - start).count();
  const auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  u.cpu_seconds = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  u.peak_rss_mib = usage.ru_maxrss / 1024.0;  // Linux reports KiB
  sampler.Report(&u);
  const auto [steal_after, total_after] = StealAndTotalJiffies();
  if (total_before > 0 && total_after > total_before) {
    u.host_steal = (steal_after - steal_before) / (total_after - total_before);
  }
  if (WIFEXITED(status)) u.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) u.signal = WTERMSIG(status);
  return u;
}

}  // namespace sapmvs

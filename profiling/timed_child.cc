#include "timed_child.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
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
  int status = 0;
  rusage usage{};
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) throw Error(std::string("wait4: ") + strerror(errno));
  }
  if (exec_failed) throw Error(command.argv[0] + ": cannot run: " + strerror(exec_errno));
  ChildUsage u;
  u.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  u.cpu_seconds = seconds(usage.ru_utime) + seconds(usage.ru_stime);
  u.peak_rss_mib = usage.ru_maxrss / 1024.0;  // Linux reports KiB
  const auto [steal_after, total_after] = StealAndTotalJiffies();
  if (total_before > 0 && total_after > total_before) {
    u.host_steal = (steal_after - steal_before) / (total_after - total_before);
  }
  if (WIFEXITED(status)) u.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) u.signal = WTERMSIG(status);
  return u;
}

}  // namespace sapmvs

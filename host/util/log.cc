#include "sapmvs/util/log.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <iostream>
#include <memory>
#include <mutex>
#include <streambuf>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// One lock for the log file and the console writes of detail lines: lines
// come from OpenMP workers (GDAL's warnings) as well as the main thread.
std::mutex& LogMutex() {
  static std::mutex m;
  return m;
}

struct LogState {
  int verbosity = 0;
  int fd = -1;  // the log file, O_APPEND; -1 = none
  std::streambuf* console_out = nullptr;
  std::streambuf* console_err = nullptr;
};
LogState& State() {
  static LogState s;
  return s;
}

// Appends one timestamped line to the log file; the caller holds the lock.
void WriteLogLine(const char* tag, const std::string& line) {
  const int fd = State().fd;
  if (fd < 0) return;
  std::string text = Iso8601Utc(std::chrono::system_clock::now()) + " " + tag + " " + line + "\n";
  const char* p = text.data();
  size_t left = text.size();
  // A log that cannot be written must not stop the run it describes.
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n > 0) {
      p += n;
      left -= static_cast<size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;
    }
  }
}

// Passes everything on to the console's buffer and copies whole lines into
// the log file. A '\r' ends a line too, so redrawn text does not pile up.
class TeeBuffer : public std::streambuf {
 public:
  TeeBuffer(std::streambuf* console, const char* tag) : console_(console), tag_(tag) {}
  ~TeeBuffer() override { FlushPartial(); }

  void FlushPartial() {
    std::lock_guard<std::mutex> lock(LogMutex());
    if (!partial_.empty()) WriteLogLine(tag_, partial_);
    partial_.clear();
  }

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    const char ch = static_cast<char>(c);
    return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    const std::streamsize written = console_->sputn(s, n);
    std::lock_guard<std::mutex> lock(LogMutex());
    for (std::streamsize i = 0; i < n; ++i) {
      if (s[i] == '\n' || s[i] == '\r') {
        if (!partial_.empty()) WriteLogLine(tag_, partial_);
        partial_.clear();
      } else {
        partial_ += s[i];
      }
    }
    return written;
  }
  int sync() override { return console_->pubsync(); }

 private:
  std::streambuf* console_;
  const char* tag_;
  std::string partial_;
};

std::unique_ptr<TeeBuffer>& OutTee() {
  static std::unique_ptr<TeeBuffer> t;
  return t;
}
std::unique_ptr<TeeBuffer>& ErrTee() {
  static std::unique_ptr<TeeBuffer> t;
  return t;
}

}  // namespace

std::string LogOptions::Problem() const {
  if (verbosity < 0) return "a verbosity >= 0 (verbosity = " + std::to_string(verbosity) + ")";
  return "";
}

void StartLog(const LogOptions& options, const std::string& command_line) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("log: expected " + problem);
  LogState& s = State();
  s.verbosity = options.verbosity;
  if (options.file.empty() || s.fd >= 0) return;
  const int fd = ::open(options.file.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw Error("--log " + options.file.string() + ": cannot open for appending (" +
                std::strerror(errno) + ")");
  }
  {
    std::lock_guard<std::mutex> lock(LogMutex());
    s.fd = fd;
    WriteLogLine("start ", command_line);
  }
  std::cout.flush();
  s.console_out = std::cout.rdbuf();
  s.console_err = std::cerr.rdbuf();
  OutTee() = std::make_unique<TeeBuffer>(s.console_out, "stdout");
  ErrTee() = std::make_unique<TeeBuffer>(s.console_err, "stderr");
  std::cout.rdbuf(OutTee().get());
  std::cerr.rdbuf(ErrTee().get());
}

void EndLog(int exit_code) {
  LogState& s = State();
  s.verbosity = 0;
  if (s.fd < 0) return;
  std::cout.flush();
  std::cerr.flush();
  std::cout.rdbuf(s.console_out);
  std::cerr.rdbuf(s.console_err);
  OutTee()->FlushPartial();
  ErrTee()->FlushPartial();
  std::lock_guard<std::mutex> lock(LogMutex());
  WriteLogLine("exit  ", std::to_string(exit_code));
  ::close(s.fd);
  s.fd = -1;
}

void LogDetail(const std::string& line) {
  std::lock_guard<std::mutex> lock(LogMutex());
  const LogState& s = State();
  if (s.verbosity > 0) {
    // The console's own buffer: through std::cerr the line would be logged
    // twice, once as stderr.
    std::streambuf* err = s.console_err ? s.console_err : std::cerr.rdbuf();
    const std::string text = line + "\n";
    err->sputn(text.data(), static_cast<std::streamsize>(text.size()));
    err->pubsync();
  }
  WriteLogLine("detail", line);
}

bool LogVerbose() { return State().verbosity > 0; }

std::string Iso8601Utc(std::chrono::system_clock::time_point t) {
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count();
  const std::time_t secs = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[40];
  const size_t n = std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%S", &tm);
  std::snprintf(buf + n, sizeof(buf) - n, ".%03dZ", static_cast<int>(ms % 1000));
  return buf;
}

}  // namespace sapmvs

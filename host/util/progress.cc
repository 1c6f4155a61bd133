#include "sapmvs/util/progress.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace sapmvs {

bool Progress::TerminalAllowsProgress() {
  const char* ci = std::getenv("CI");
  if (ci && *ci && std::string(ci) != "false" && std::string(ci) != "0") return false;
  return ::isatty(STDERR_FILENO) == 1;
}

Progress::Progress(std::string label, long total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      active_(enabled && TerminalAllowsProgress()),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::seconds(1)) {
  if (active_) Draw("");
}

Progress::~Progress() { Finish(); }

void Progress::Advance(long steps, const std::string& note) {
  done_ += steps;
  if (!active_) return;
  const auto now = std::chrono::steady_clock::now();
  // Redraw at most 10 times a second; the last step always shows.
  if (done_ < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  Draw(note);
}

void Progress::Finish() {
  if (!active_ || finished_) return;
  finished_ = true;
  Draw("");
  std::fputc('\n', stderr);
}

void Progress::Draw(const std::string& note) {
  constexpr int kWidth = 30;
  const double frac = total_ > 0 ? std::min(1.0, static_cast<double>(done_) / total_) : 1.0;
  const int fill = static_cast<int>(frac * kWidth);
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r%-18s [%.*s%*s] %ld/%ld %5.1fs %-30.30s", label_.c_str(), fill,
               "##############################", kWidth - fill, "", done_, total_, secs,
               note.c_str());
  std::fflush(stderr);
}

}  // namespace sapmvs

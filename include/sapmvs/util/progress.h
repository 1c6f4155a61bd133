#pragma once
// Progress on a terminal: a bar redrawn in place on stderr. Quiet when stderr
// is not a terminal, when CI is set, or when asked (--quiet).

#include <chrono>
#include <string>

namespace sapmvs {

class Progress {
 public:
  // `total` steps of `label`. `enabled` = false silences it whatever the terminal.
  Progress(std::string label, long total, bool enabled = true);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Advance(long steps = 1, const std::string& note = "");
  void Finish();
  bool active() const { return active_; }

  // True when progress may be drawn: stderr is a terminal and CI is not set.
  static bool TerminalAllowsProgress();

 private:
  void Draw(const std::string& note);

  std::string label_;
  long total_;
  long done_ = 0;
  bool active_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace sapmvs

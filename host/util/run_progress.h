#pragma once
// `run`'s progress: one status line redrawn in place on a terminal (group
// i/N, the stage and its detail, elapsed time, ETA), and one line per matched
// group left in the scrollback. Silent when stderr is not a terminal, under
// CI, or with --quiet (Progress::TerminalAllowsProgress).

#include <chrono>
#include <cstdio>
#include <string>

#include "sapmvs/util/match_progress.h"

namespace sapmvs {

class RunProgress {
 public:
  // `groups` to match in this call and their `images` in all; `out` is
  // stderr in `run`, a memory stream in tests (enabled there by the caller).
  RunProgress(int groups, long images, bool enabled, std::FILE* out = stderr);

  void StartGroup(int index, int group_count, long group_images);
  void Update(const MatchProgressEvent& e);
  // The group's line; with its measured peak RSS and the plan's estimate
  // (bytes) when both are > 0.
  void EndGroup(long points, double peak_rss_bytes = 0, double estimate_bytes = 0);
  // Clears the status line (before the run's summary is printed).
  void Finish();

  // "1:02:03" or "2:03". Exposed for tests.
  static std::string Clock(double seconds);
  // The status line as drawn now, without the carriage return.
  std::string Line() const;
  // Seconds left, from the mean time per image of the groups matched so far
  // in this call; < 0 before the first group has ended.
  double EtaSeconds() const;

 private:
  double Elapsed() const;

  bool enabled_;
  std::FILE* out_;
  long images_, images_done_ = 0, group_images_ = 0;
  int index_ = 0, group_count_ = 0;
  double matched_seconds_ = 0;  // of the groups ended
  MatchProgressEvent last_;
  std::chrono::steady_clock::time_point start_, group_start_, last_draw_;
  size_t drawn_ = 0;  // width of the line on screen
};

}  // namespace sapmvs

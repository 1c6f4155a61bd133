#pragma once
// What a group's matching is doing, for a progress display: the matcher
// reports, the caller (one status line in `run`) draws.

#include <functional>
#include <string>

namespace sapmvs {

struct MatchProgressEvent {
  std::string stage;  // load, features, seeds, edges, propagation, filter
  long done = 0;      // units of the stage done so far, of `total` (0: unknown)
  long total = 0;
  std::string detail;  // e.g. "pass 2, wave 14, 35,120 points"
};

using MatchProgressFn = std::function<void(const MatchProgressEvent&)>;

}  // namespace sapmvs

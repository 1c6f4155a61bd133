#include "sapmvs/match/matcher_options.h"

#include <iostream>

#include "sapmvs/util/error.h"

namespace sapmvs {

std::string ToString(MatchMode mode) { return mode == MatchMode::kSapmvs ? "sapmvs" : "pmvs"; }

MatchMode ParseMatchMode(const std::string& text) {
  if (text == "sapmvs") return MatchMode::kSapmvs;
  if (text == "pmvs") return MatchMode::kPmvs;
  throw Error("unknown matching mode '" + text + "': expected sapmvs or pmvs");
}

std::string MatcherOptions::Problem() const {
  if (std::string p = FirstRangeProblem(*this); !p.empty()) return p;
  if (!(threshold_before <= threshold))
    return "threshold_before <= threshold (threshold_before = " + OptionText(threshold_before) +
           ", threshold = " + OptionText(threshold) + ")";
  if (!(canny_low <= canny_high))
    return "canny_low <= canny_high (canny_low = " + OptionText(canny_low) +
           ", canny_high = " + OptionText(canny_high) + ")";
  if (!(pmvs_passes <= expand_iterations))
    return "pmvs_passes <= expand_iterations (pmvs_passes = " + OptionText(pmvs_passes) +
           ", expand_iterations = " + OptionText(expand_iterations) + ")";
  // PMVS uses window_size alone and ignores the order of adaptive_sizes.
  if (mode == MatchMode::kSapmvs) {
    if (adaptive_sizes.empty() || adaptive_sizes.back() != window_size) {
      return "adaptive_sizes ending with window_size (adaptive_sizes = " +
             OptionText(adaptive_sizes) + ", window_size = " + OptionText(window_size) + ")";
    }
    for (size_t i = 1; i < adaptive_sizes.size(); ++i) {
      if (adaptive_sizes[i] >= adaptive_sizes[i - 1])
        return "adaptive_sizes decreasing (adaptive_sizes = " + OptionText(adaptive_sizes) + ")";
    }
  }
  return "";
}

bool MatcherOptions::Check() const {
  const std::string problem = Problem();
  if (!problem.empty()) std::cerr << "MatcherOptions: expected " << problem << "\n";
  return problem.empty();
}

}  // namespace sapmvs

#include "sapmvs/run/run_options.h"

#include <iostream>

namespace sapmvs {

std::string RunOptions::Problem() const {
  if (block.empty()) return "a block path";
  if (out.empty()) return "an output folder (--out)";
  if (std::string p = matcher.Problem(); !p.empty()) return p;
  if (std::string p = grouping.Problem(); !p.empty()) return p;
  if (std::string p = FirstRangeProblem(*this); !p.empty()) return p;
  if (std::string p = dsm.Problem(); !p.empty()) return "DSM " + p;
  return "";
}

bool RunOptions::Check() const {
  const std::string p = Problem();
  if (!p.empty()) std::cerr << "RunOptions: expected " << p << "\n";
  return p.empty();
}

}  // namespace sapmvs

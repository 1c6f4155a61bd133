#include "sapmvs/run/run_options.h"

#include <iostream>
#include <sstream>

namespace sapmvs {

std::string RunOptions::Problem() const {
  if (block.empty()) return "a block path";
  if (out.empty()) return "an output folder (--out)";
  if (device.find(',') != std::string::npos) {
    std::istringstream entries(device + ",");
    for (std::string entry; std::getline(entries, entry, ',');) {
      if (entry.find_first_not_of(" \t") == std::string::npos) {
        return "--device as a comma list without empty entries, e.g. 0,1 (got '" + device + "')";
      }
    }
  }
  if (std::string p = matcher.Problem(); !p.empty()) return p;
  if (std::string p = grouping.Problem(); !p.empty()) return p;
  if (std::string p = FirstRangeProblem(*this); !p.empty()) return p;
  if (std::string p = dsm.Problem(); !p.empty()) return "DSM " + p;
  if (std::string p = ortho.Problem(); !p.empty()) return "orthophoto " + p;
  return "";
}

bool RunOptions::Check() const {
  const std::string p = Problem();
  if (!p.empty()) std::cerr << "RunOptions: expected " << p << "\n";
  return p.empty();
}

}  // namespace sapmvs

#pragma once
// `sapmvs run`: one block matched as one group, written as DIR/cloud.ply
// (binary, world coordinates in double, CRS in the header) and
// DIR/report.json (points, per-stage wall and device times, kernel times).
#include <filesystem>
#include <iosfwd>
#include <string>

#include "sapmvs/matcher.h"

namespace sapmvs {

struct RunOptions {
  std::filesystem::path block;  // any format ReadBlock takes
  std::filesystem::path out;    // output folder, created when missing
  // OpenCL device: index or name substring ("" = SAPMVS_DEVICE, else the default).
  std::string device;
  MatcherOptions matcher;
  bool Check() const;
};

struct RunReport {
  std::filesystem::path cloud_path;
  std::filesystem::path report_path;
  std::string device;
  double total_seconds = 0;
  MatchStats stats;
};

// Throws Error for bad options or input, NoDeviceError without a device.
// Outputs are written atomically: a failed run leaves no partial file.
RunReport RunDense(const RunOptions& options);

// The summary printed after a run.
void PrintRunSummary(const RunReport& report, std::ostream& out);

}  // namespace sapmvs

#pragma once
// versus_pmvs2's second table: the clouds compared without ground truth, as
// a real block must be (local_noise.h): the ground each covers on cells of
// 4 GSD, as a share of what all of them cover; its local noise; for a
// sapmvs run of several groups, the noise of each group's own cloud before
// the merge and the share of the matched points the merge dropped as
// another group's duplicates; for a sapmvs run, its kernels' NCC evaluations
// (one window in one view pair) per point of its cloud: the work, which
// device and clock do not change.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/evaluate/local_noise.h"
#include "sapmvs/io/ply_io.h"

namespace sapmvs {

struct SurfaceRow {
  std::string name;
  const PointCloud* cloud = nullptr;
  // A sapmvs run's output folder (report.json, groups/), empty for PMVS2.
  std::filesystem::path run;
};

// The table in markdown, distances in CRS units. `gsd_level`: the GSD of the
// level matched (> 0).
std::string SurfaceTable(const std::vector<SurfaceRow>& rows, double gsd_level);

}  // namespace sapmvs

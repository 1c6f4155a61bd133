#pragma once
// `sapmvs run --profile`: where the time of a run went. Per kernel: launches,
// work items, total / mean / max device time, items/s and NCC evaluations/s,
// and from a cost model estimated bytes and flops, hence GB/s and GFLOP/s.
// Per phase: wall, device and host time. Printed as tables sorted by time and
// written as CSV and JSON.
//
// Cost model of one NCC evaluation (one patch in one view, mu x mu samples),
// per sample, counted from kernels/ncc_score.cl (patch_refine.cl evaluates
// the same way):
//   flops: 2 projections (3 dot products of 4 = 21 flops, 2 divides) = 46,
//          2 bilinear samples (8 multiply-adds + 2 fractions) = 20, the grid
//          step (6) and the NCC sums (mean 2, deviations 2, products 3,
//          sums 3) = 10: kNccFlopsPerSample = 82;
//   bytes: 2 bilinear samples of 4 float32 = 32: kNccBytesPerSample (reads
//          from global memory, most served by caches, so GB/s is the demand
//          the kernel puts on the memory system, not DRAM traffic).
// Patch, camera and result records are per evaluation, not per sample, and
// left out; refinement counts every candidate as evaluated (an upper bound).
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "sapmvs/match/match_stats.h"
#include "sapmvs/run/run_result.h"

namespace sapmvs {

inline constexpr double kNccFlopsPerSample = 82;
inline constexpr double kNccBytesPerSample = 32;

struct KernelProfile {
  std::string kernel;
  long launches = 0;
  long items = 0;
  double ncc_evaluations = 0;
  double seconds = 0, mean_ms = 0, max_ms = 0;
  double items_per_second = 0, evaluations_per_second = 0;
  double bytes = 0, flops = 0, gb_per_second = 0, gflop_per_second = 0;
};
// Sorted by device time, largest first.
std::vector<KernelProfile> ProfileKernels(const MatchStats& stats);

struct PhaseProfile {
  std::string phase;
  double wall = 0, device = 0;
  double cpu = 0;              // process CPU seconds; 0 for the run's own phases (not measured)
  double ncc_evaluations = 0;  // of the phase's kernels (StageTime::ncc_evaluations)
  double host() const { return wall - device; }
};
// Matching stages (summed over groups), then the run's own; sorted by wall time.
std::vector<PhaseProfile> ProfilePhases(const RunReport& report);

void PrintProfile(const RunReport& report, std::ostream& out);
// Writes `csv` (one row per kernel, then per phase, a `kind` column telling
// which) and the same as JSON beside it (`csv` with extension .json),
// atomically.
void WriteProfile(const RunReport& report, const std::filesystem::path& csv);

}  // namespace sapmvs

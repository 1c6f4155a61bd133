#pragma once
// What matching one group did and how long it took: counts, per-stage and
// per-kernel times. The matcher fills them; the run sums, reports and
// checkpoints them.
#include <algorithm>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace sapmvs {

// Wall and device time of one stage, seconds.
struct StageTime {
  double wall = 0;
  double device = 0;
  // Process CPU seconds (every thread's) during the stage: cpu / wall is how
  // busy it kept the cores.
  double cpu = 0;
  // Peak RSS at the stage's end: the group's so far where the run reset the
  // peak at its start (ResetPeakRss), else the process's; over a run's
  // groups, the highest.
  double peak_rss_bytes = 0;
  // NCC evaluations of the stage's kernels (KernelTime::ncc_evaluations):
  // the work, comparable across devices and commits.
  double ncc_evaluations = 0;
};

struct KernelTime {
  long launches = 0;
  long items = 0;  // work items: patches (refinement) or (patch, view) pairs (scoring)
  // NCC evaluations of one patch in one view pair, each over patch_size^2
  // samples: one per pair for scoring; for refinement the sum over patches
  // of views * the candidates the kernel scored (a view whose samples leave
  // the image stops a candidate's score early, so this is an upper bound).
  double ncc_evaluations = 0;
  int patch_size = 0;
  double seconds = 0;      // device time, summed (0 without queue profiling)
  double max_seconds = 0;  // of one launch
};

// Adds t's launches to *sum (the same kernel, from another engine or group).
inline void AddKernelTime(const KernelTime& t, KernelTime* sum) {
  sum->launches += t.launches;
  sum->items += t.items;
  sum->ncc_evaluations += t.ncc_evaluations;
  sum->patch_size = t.patch_size;
  sum->seconds += t.seconds;
  sum->max_seconds = std::max(sum->max_seconds, t.max_seconds);
}

// Adds t to the stage called `name` in *stages, or appends it: stages
// repeated by the expand-filter passes, or over a run's groups, add up under
// one name (the peak RSS: the higher).
inline void AddStageTime(const std::string& name, const StageTime& t,
                         std::vector<std::pair<std::string, StageTime>>* stages) {
  auto same =
      std::find_if(stages->begin(), stages->end(), [&](const auto& s) { return s.first == name; });
  if (same == stages->end()) {
    stages->emplace_back(name, t);
    return;
  }
  same->second.wall += t.wall;
  same->second.device += t.device;
  same->second.cpu += t.cpu;
  same->second.ncc_evaluations += t.ncc_evaluations;
  same->second.peak_rss_bytes = std::max(same->second.peak_rss_bytes, t.peak_rss_bytes);
}

struct MatchStats {
  int images = 0;
  long features = 0;
  long seeds_tried = 0;
  long seeds_accepted = 0;
  long edge_points = 0;
  long matched_edge_points = 0;
  long candidates = 0;  // patches refined during propagation
  long patches = 0;     // accepted (seeds + propagation)
  long waves = 0;
  long largest_wave = 0;
  std::map<int, long> accepted_by_size;  // sapmvs: patch side -> accepted patches
  long pmvs_pass_patches = 0;            // sapmvs: of `patches`, pmvs_passes' (one cell each)
  long points_before_filter = 0;
  double score_floor = 0;            // the score fence's value (>= threshold)
  double pmvs_pass_score_floor = 0;  // sapmvs: the fence of pmvs_passes' one-cell patches
  double plane_tolerance = 0;        // the neighbourhood test's, footprints (last pass)
  long removed_score = 0;            // below their floor (score_floor, pmvs_pass_score_floor)
  long removed_visibility = 0;
  long removed_neighbourhood = 0;
  long removed_clusters = 0;
  long removed_depth_range = 0;  // far outside the depths the image's seeds span
  long removed_unfitted = 0;     // sapmvs: off the centre of a plane no neighbour confirms
  long points = 0;
  std::vector<std::pair<std::string, StageTime>> stages;  // in order
  std::map<std::string, KernelTime> kernels;
  double gsd = 0;  // median footprint of a pixel at the working level, block units
};

}  // namespace sapmvs

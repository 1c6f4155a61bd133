#pragma once
// Dense matching of one group of images (method.md 3 and 4): seeds from
// Harris / DoG features matched along epipolar lines, propagation in waves
// refined and scored by the patch kernels (an OpenCL device or the CPU
// reference, host/patch_kernels.h), then filtering. Two modes share
// the engine: `sapmvs` (the paper's self-adaptive patch) and `pmvs`
// (Furukawa's one-patch-per-cell expansion).
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "sapmvs/block.h"
#include "sapmvs/match_progress.h"
#include "sapmvs/ply_io.h"

namespace sapmvs {

struct BlockGeometry;

class PatchKernels;

enum class MatchMode { kSapmvs, kPmvs };
std::string ToString(MatchMode mode);
// Throws Error naming `text` unless it is "sapmvs" or "pmvs".
MatchMode ParseMatchMode(const std::string& text);

struct MatcherOptions {
  MatchMode mode = MatchMode::kSapmvs;
  // Pyramid level the group is matched at: 0 = full resolution, 1 = half
  // (PMVS2's `level`), ... Each level halves both image sides.
  int level = 1;
  // Side of an image cell in pixels at `level` (PMVS2's `csize`): the grid
  // that says which parts of an image are already covered.
  int cell_size = 2;
  // Mean NCC over the accepted views a patch needs after optimisation
  // (PMVS2's `threshold`), and the per-view NCC a view needs to count.
  double threshold = 0.7;
  // Per-view NCC a view needs before optimisation to take part in it.
  double threshold_before = 0.4;
  // Images (reference included) a patch must be photo-consistent in
  // (PMVS2's `minImageNum`), 2 to kMaxViews.
  int min_image_num = 3;
  // PMVS2's `maxAngle`, degrees: a patch is accepted only if some pair of
  // the images it is matched in (the reference included) meets at it at more
  // than this (and less than view_angle_deg), so that its depth is
  // constrained. Each view on its own may be narrower: at the paper's 88 %
  // forward overlap every neighbour of an image is (4 degrees apart).
  double max_angle_deg = 10.0;
  // Largest angle, degrees, between a patch normal and the direction to an
  // image for that image to be a visible view of the patch.
  double view_angle_deg = 60.0;
  // Side of the matching window (PMVS2's `wsize`), pixels, odd: the patch
  // refined by the device, and the smallest adaptive patch.
  int window_size = 7;
  // Self-adaptive patch sides tried in order, pixels, odd, decreasing, each
  // <= kMaxPatchSize; the last must equal window_size (sapmvs mode).
  std::vector<int> adaptive_sizes = {21, 15, 11, 7};
  // sapmvs: NCC sample weights. Each sample of a window counts
  // exp(-d^2 / 2 s^2), d its difference from the window's centre sample in
  // the reference image and s this many standard deviations of the 3 x 3
  // samples around the centre, so that a window straddling a wall, a roof
  // edge or a crown scores the surface under its centre rather than failing
  // or settling on a depth between the two. Relative, so one value suits
  // scans and renderings of any contrast; smaller is sharper at edges but
  // noisier on weak texture (on `small` with 4 features per block, 1.5:
  // 73.0 % coverage; 3: 72.4 %; NGI keeps 87 % of its points at 3, 76 % at
  // 2). 0 = plain NCC; pmvs mode always scores plain NCC, as PMVS does.
  double ncc_sigma_color = 3.0;
  // Features kept per detector per 32 x 32 pixel block (PMVS: 4). 8 seeds
  // the roofs that 4 left without a single right seed: on `small` coverage
  // 72.4 -> 75.5 % (sapmvs) and 63.8 -> 64.9 % (pmvs) at the same accuracy
  // and time; NGI gains points in both modes.
  int features_per_block = 8;
  // Candidate matches lie within this many pixels of the epipolar line.
  double epipolar_distance = 2.0;
  // Candidates tried per feature, best ordered first.
  int candidates_per_feature = 4;
  // Canny thresholds on 8-bit grey for edge points; edge pixels matched
  // along epipolar lines become propagation barriers (sapmvs mode).
  double canny_low = 40;
  double canny_high = 120;
  bool use_edges = true;
  // Expand-then-filter passes (PMVS: n = 3). Each pass after the first frees
  // the cells of the points the filter removed and grows the surviving
  // patches into them again.
  int expand_iterations = 3;
  // Most candidate patches one device launch takes.
  int max_wave = 16384;
  // Waves stop after this many (0 = until the front is empty).
  int max_waves = 0;
  // Score fence, in robust standard deviations (1.4826 x MAD): points of a
  // patch scoring further than this below the median score of the first
  // expansion's points go (0 = off). Most points are right, so their scores
  // show what a right match scores on these images (their noise and
  // texture): about 0.98 on the simulator's, 0.89 on NGI's scans; a fixed
  // `threshold` (0.7, the floor) cannot be both.
  double score_fence = 3.0;
  // Filtering: depth agreement tolerance, in pixel footprints.
  double depth_tolerance = 3.0;
  // Neighbourhood test: neighbours within this many footprints of a point.
  double neighbour_radius = 4.0;
  // A point needs this many neighbours, and must lie within the plane
  // tolerance of the plane they fit; a patch's plane must pass within it of
  // most neighbouring points of other patches. The tolerance is
  // plane_sigmas robust standard deviations of the distances between
  // neighbouring patches (how noisy this group's depths are), and at least
  // plane_tolerance footprints. Half a footprint (one full-resolution GSD at
  // level 1): a fixed 1.5 let a quarter of the sapmvs points on
  // `simulate --preset small` stray beyond 1 GSD.
  int min_neighbours = 4;
  double plane_tolerance = 0.5;
  double plane_sigmas = 1.5;
  // Clusters (points linked within neighbour_radius) smaller than this are
  // removed.
  int min_cluster_size = 30;
  // Show progress on a terminal.
  bool progress = true;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
  // The first failing condition as "what was expected (name = value)", or ""
  // when the options are valid; for callers that report errors themselves.
  std::string Problem() const;
};

// Wall and device time of one stage, seconds.
struct StageTime {
  double wall = 0;
  double device = 0;
  double peak_rss_bytes = 0;  // the process's peak so far, at the stage's end
};

struct KernelTime {
  long launches = 0;
  long items = 0;  // work items: patches (refinement) or (patch, view) pairs (scoring)
  // NCC evaluations of one patch in one view pair, each over patch_size^2
  // samples: one per pair for scoring; for refinement the upper bound
  // sum over patches of views * (1 + 6 * rounds), rounds = min(iterations,
  // moves + max_halvings) (a candidate that
  // leaves the image stops early).
  double ncc_evaluations = 0;
  int patch_size = 0;
  double seconds = 0;      // device time, summed (0 without queue profiling)
  double max_seconds = 0;  // of one launch
};

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
  long points_before_filter = 0;
  double score_floor = 0;      // the score fence's value (>= threshold)
  double plane_tolerance = 0;  // the neighbourhood test's, footprints (last pass)
  long removed_score = 0;      // below score_floor
  long removed_visibility = 0;
  long removed_neighbourhood = 0;
  long removed_clusters = 0;
  long removed_depth_range = 0;  // far outside the depths the image's seeds span
  long points = 0;
  std::vector<std::pair<std::string, StageTime>> stages;  // in order
  std::map<std::string, KernelTime> kernels;
  double gsd = 0;  // median footprint of a pixel at the working level, block units
};

struct MatchResult {
  PointCloud cloud;  // world coordinates (the local origin added back)
  MatchStats stats;
};

// Matches images `image_ids` of `block` (all when empty) with `kernels`
// (MakePatchKernels). `geometry`:
// EstimateBlockGeometry(block) when the caller already has it, else nullptr.
// `on_progress` hears each stage and wave; without it, options.progress
// draws a status line of its own on a terminal. Throws Error for bad
// options, unreadable images or fewer than 2 usable images.
MatchResult MatchGroup(const Block& block, const std::vector<int>& image_ids,
                       const MatcherOptions& options, PatchKernels& kernels,
                       const BlockGeometry* geometry = nullptr,
                       const MatchProgressFn& on_progress = {});

// What matching one group holds, per unit, for the planner's memory model
// (grouping.h EstimateGroupMemory, which spells out each term): per pixel of
// the group's images on the device and on the host, per image cell, and per
// candidate of a wave on both sides, with kMaxViews - 1 views to a patch.
struct MatcherMemoryModel {
  double device_bytes_per_pixel = 0;
  double host_bytes_per_pixel = 0;
  double host_bytes_per_cell = 0;
  double device_bytes_per_candidate = 0;
  double host_bytes_per_candidate = 0;
};
MatcherMemoryModel MatcherMemory();

}  // namespace sapmvs

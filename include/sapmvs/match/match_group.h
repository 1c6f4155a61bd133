#pragma once
// Dense matching of one group of images (method.md 3 and 4): seeds from
// Harris / DoG features matched along epipolar lines, propagation in waves
// refined and scored by the patch kernels (an OpenCL device or the CPU
// reference, host/match/patch_kernels.h), then filtering. Two modes share
// the engine: `sapmvs` (the paper's self-adaptive patch) and `pmvs`
// (Furukawa's one-patch-per-cell expansion).
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/match/ground_region.h"
#include "sapmvs/match/match_stats.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/util/match_progress.h"

namespace sapmvs {

struct BlockGeometry;
class LevelImageStore;

class PatchKernels;

struct MatchResult {
  PointCloud cloud;  // world coordinates (the local origin added back)
  MatchStats stats;
};

// Matches images `image_ids` of `block` (all when empty) with `kernels`
// (MakePatchKernels); `view_ids` are matched in as views only, never as a
// patch's reference (ImageGroup::views). `geometry`:
// EstimateBlockGeometry(block) when the caller already has it, else nullptr.
// `on_progress` hears each stage and wave; without it, options.progress
// draws a status line of its own on a terminal. `region`: the ground the
// group owns; no patch grows outside it. `levels`: the run's store of
// images at the level (level_images.h), which groups share; nullptr decodes
// each image for this group. Throws Error for bad options, unreadable images
// or fewer than 2 usable images.
MatchResult MatchGroup(const Block& block, const std::vector<int>& image_ids,
                       const MatcherOptions& options, PatchKernels& kernels,
                       const BlockGeometry* geometry = nullptr,
                       const MatchProgressFn& on_progress = {},
                       const std::vector<int>& view_ids = {},
                       const GroundRegion& region = GroundRegion(),
                       const LevelImageStore* levels = nullptr);

// Images the load and the colours' read decode side by side (fewer on fewer
// host threads): each is one core's work for tens of milliseconds, and each
// holds its full-resolution pixels and an undistorted copy while it is read.
constexpr int kImagesReadAtOnce = 2;

// What loading GDAL adds to a process that matches `block` (GdalBytesToLoad):
// the first group loads it where an image is of a format only GDAL decodes;
// JPEG and PNG are decoded without it, and a run then loads it for its
// outputs only, once the groups are matched (0).
double GdalBytesToMatch(const Block& block);

// What matching one group holds, per unit, for the planner's memory model
// (grouping.h EstimateGroupMemory, which spells out each term): per pixel of
// the group's images on the device and on the host, per pixel that can take
// points, and per candidate of a wave on both sides, with kMaxViews - 1
// views to a patch.
struct MatcherMemoryModel {
  double device_bytes_per_pixel = 0;
  double host_bytes_per_pixel = 0;
  double host_bytes_per_point_pixel = 0;  // per pixel that can take points
  double device_bytes_per_candidate = 0;
  double host_bytes_per_candidate = 0;
  // What the process gains once, in its first group, and keeps: the kernels
  // the device runtime compiles (PoCL in-process), the thread pool's stacks
  // and heaps, the library code first run. Measured on PoCL (tiny, 2 threads):
  // the RSS between planning and the second group's start grew by 22 MiB,
  // 13 anonymous and 9 of library code.
  double runtime_warmup_bytes = 0;
};
MatcherMemoryModel MatcherMemory();

}  // namespace sapmvs

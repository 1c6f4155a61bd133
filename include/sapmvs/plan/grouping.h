#pragma once
// Image grouping (method.md 2): a block of hundreds of images does not fit in
// memory at once, so it is split into small groups that are matched
// independently and merged. Two strategies:
//   strip      (paper) runs of at most max_images consecutive images within
//              one flight strip, the last run of a strip taking the
//              remainder (16 -> 6+6+4, 17 -> 6+6+5: the paper's Table 3)
//              when it has 4 or more;
//   footprint  (ours) the ground extent is tiled and each tile gets the
//              images that see it best, across strips, so that side overlap
//              also contributes views.
// Both bound a group by a memory estimate as well as by a count. Groups
// overlap on the ground; the merge gives each XY to the group whose `center`
// is nearest.
#include <Eigen/Core>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/plan/grouping_options.h"

namespace sapmvs {

struct BlockGeometry;

struct GroupMemory {
  // The device's own memory: what a GPU must hold. A device that shares the
  // host's memory (PoCL's CPU device) reads the host's grey in place and
  // holds only the wave's buffers, which `host_bytes` counts too.
  double device_bytes = 0;
  double host_bytes = 0;
  // The process before the group: the program and its libraries, the OpenCL
  // runtime, the block (GroupingPlan::process_bytes). Matching adds
  // host_bytes to it, so their sum is what the process peaks at.
  double process_bytes = 0;
  // The process's peak while it matches the group: what memory_budget
  // bounds, and what the run measures (report.json memory_measured_bytes).
  double Total() const { return host_bytes + process_bytes; }
};

// Memory to match `images` of `block` at `level`, in bytes. With, for image
// i, P_i its pixels at the level (sides halved per level as
// Intrinsics::Scaled rounds them), s_i the share of them that can take
// points (`cell_shares`: 1 for a group that owns all its images' ground,
// the share of the footprint within its tile for a footprint group's image,
// 0 for a view, which is never a reference; all 1 when empty), and
// M = max_wave:
//   device = sum_i 4 P_i                      float32 grey, resident for the
//                                             group
//          + W = M (48 + 48 + 4 + 16 (V - 1)) one wave: NccPatch, refined
//                                             patch, view offset, and per
//                                             view a pair, an index, a score
//   host   = sum_i (5 + 13 s_i) P_i           float32 grey + edge mask
//                                             (colours are read again at
//                                             the end), and per pixel that
//                                             can take points 13 bytes,
//                                             fitted to the measured peaks:
//                                             the cell grids, the accepted
//                                             patches and dense points, the
//                                             filter's arrays (MatcherMemory)
//          + W + M (candidate + result + 4 (V - 1))   the wave, both sides
//          + R max_i 6 w_i h_i               loading (and the colours'
//                                             read): R = kImagesReadAtOnce
//                                             full-resolution BGR images,
//                                             raw + undistorted
// with V = kMaxViews and w_i h_i the full-resolution size. The per-image
// terms grow linearly with the images and by 4x per level towards full
// resolution; the wave is bounded by max_wave and the loading peak by the
// largest image, whatever the group. Throws Error for an index outside the
// block, a level outside 0..6, or cell_shares of another size than images
// or outside [0, 1].
GroupMemory EstimateGroupMemory(const Block& block, const std::vector<int>& images, int level);
// The same for the wave size and level of `matcher`.
GroupMemory EstimateGroupMemory(const Block& block, const std::vector<int>& images,
                                const MatcherOptions& matcher,
                                const std::vector<double>& cell_shares = {});

struct ImageGroup {
  std::vector<int> images;  // indices into block.images, in flight order (strip)
                            // or best view first (footprint)
  int strip = -1;           // strip index (strip strategy), else -1
  // Images the group's patches are also matched in, never as a reference:
  // outliers that joined it, images of other strips (GroupingOptions::
  // strip_views, most overlap first), views that widen its angles.
  std::vector<int> views;
  // images, then views: every image the group loads and matches in.
  std::vector<int> MatchedIn() const {
    std::vector<int> all = images;
    all.insert(all.end(), views.begin(), views.end());
    return all;
  }
  // Local-frame XY of the group's ground centre: the mean of its images'
  // footprint centres (strip), the tile centre (footprint). The merge gives
  // each XY to the group with the nearest center.
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  // Footprint strategy: the tile, local-frame XY; both zero for strips.
  Eigen::Vector2d tile_min = Eigen::Vector2d::Zero();
  Eigen::Vector2d tile_max = Eigen::Vector2d::Zero();
  GroupMemory memory;
  // Images of the group whose footprint overlaps (>= 10 %) fewer than
  // min_image_num - 1 others of it.
  std::vector<int> short_of_views;
};

// An image that belongs to no flight strip (DetectStrips), and why. It still
// joins the group whose ground it sees best (PlanGroups), as an image or,
// when that group is full or the image sees the ground at another scale, as
// a view.
enum class OutlierKind {
  kClimb,  // height above the ground far from the strips' (climb, descent)
  kTurn,   // between two strips, off both (a turn, a side step)
  kStray,  // before the first strip or after the last, off both
};
std::string ToString(OutlierKind kind);  // "climb", "turn", "stray"

struct StripOutlier {
  int image = -1;
  OutlierKind kind = OutlierKind::kStray;
  std::string reason;  // for people: what sets it apart, with the numbers
};

struct GroupingPlan {
  // The strategy used: options.strategy, but strip for a block that does
  // not look down, which has no ground to tile.
  GroupingStrategy strategy = GroupingStrategy::kStrip;
  GroupingOptions options;  // what the plan was made with
  // The matcher it was made for: its level, cell size and wave size (the
  // memory estimate) and min_image_num (short runs, short_of_views).
  MatcherOptions matcher;
  std::vector<std::vector<int>> strips;  // detected strips, images in flight order
  std::vector<StripOutlier> outliers;    // images of no strip, in flight order
  std::vector<ImageGroup> groups;
  std::vector<int> ungrouped;  // images in no group, as images or views (see PlanGroups)
  // The whole block is one group: it has at most max_images images and fits
  // memory_budget, and splitting it would only lose views.
  bool single_group = false;
  // What the process held when it planned (PlanGroups' process_bytes), part
  // of every group's estimate and so of what memory_budget bounds.
  double process_bytes = 0;
};

// Plans the groups of `block`. A block of at most max_images images whose
// estimate fits memory_budget is one group (single_group), whatever the
// strategy: `plan` and `run` both show what this returns. Strip strategy:
// strips follow the flight (DetectStrips); a strip's last run under 4
// images moves the cuts back (13 -> 5+4+4) where the strip has the images,
// a strip under 4 images joins the nearest group with room, and the images
// of no strip (outliers: climb, turns) join the group that sees them best,
// as images or as views; a block with no strip of 4 or more images
// (terrestrial, convergent) is cut in block order as one strip, its groups
// with strip -1. Footprint strategy: images no tile chose join the group
// that sees them best. Either way every group then takes views from beyond
// it until some pair it matches in meets at its ground at 2 max_angle_deg,
// and `ungrouped` holds only images that fit in no group's budget. Throws
// sapmvs::Error for bad options, a block of fewer than 2 images, and when
// min_image_num images (at least 2) do not fit memory_budget.
// `matcher`: the options the groups will be matched with. Its level, cell
// size and wave size set the memory estimate; a strip run shorter than its
// min_image_num takes the strip images before it, and images of a group that
// overlap fewer than min_image_num - 1 others of it are reported
// (short_of_views), since they cannot be matched there.
// `geometry`: EstimateBlockGeometry(block) when the caller has it (it reads
// the block's DEM), else nullptr and it is estimated here.
// `process_bytes`: what the process that will match holds before any group
// (run: its RSS once the block is read and the device set up); with the
// runtime's warm-up (MatcherMemoryModel::runtime_warmup_bytes) it is added
// to every group's estimate. 0 = the groups' own memory only.
GroupingPlan PlanGroups(const Block& block, const GroupingOptions& options,
                        const MatcherOptions& matcher, const BlockGeometry* geometry = nullptr,
                        double process_bytes = 0);

// Like the paper's Table 3: group, image numbers (1-based), image names,
// number of images, and the memory estimate of each group.
void PrintPlan(const Block& block, const GroupingPlan& plan, std::ostream& out);
// The plan as JSON; image indices are 0-based (block order), as in the API.
nlohmann::json PlanToJson(const Block& block, const GroupingPlan& plan);

}  // namespace sapmvs

#pragma once
// What the planner's parts share: the images' ground footprints, their
// overlaps, and the memory test a group must pass (grouping.cc plans the
// groups, group_views.cc adds the images they are matched in).
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/plan/grouping.h"

namespace sapmvs {

struct BlockGeometry;

// Where each image sees the ground, local frame.
struct Footprint {
  bool valid = false;
  std::array<Eigen::Vector2d, 4> corners;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // of the corners; camera XY when invalid
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();  // bounding box
  double scene_z = 0;
  double short_side = 0;

  bool Contains(const Eigen::Vector2d& p) const {
    if (!valid || (p.array() < lo.array()).any() || (p.array() > hi.array()).any()) return false;
    // Convex quad: p is inside when it lies on one side of every edge.
    int pos = 0, neg = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d e = corners[(k + 1) % 4] - corners[k], q = p - corners[k];
      const double c = e.x() * q.y() - e.y() * q.x();
      pos += c > 0;
      neg += c < 0;
    }
    return pos == 0 || neg == 0;
  }
};

std::vector<Footprint> Footprints(const Block& block, const BlockGeometry& geometry);

// v with `precision` digits after the point, for the plan's reports.
std::string Fixed(double v, int precision);

// A group's estimate with the process around it (PlanGroups' process_bytes),
// which is what memory_budget bounds: `ids` all references of their whole
// footprints (a strip run, the block as one group).
GroupMemory EstimateInProcess(const Block& block, const std::vector<int>& ids,
                              const MatcherOptions& matcher, double process_bytes);
// The same for `g`, whose views take no points and whose images, when it has
// a tile, take them only where they see it (CellShares).
GroupMemory EstimateInProcess(const Block& block, const ImageGroup& g,
                              const std::vector<Footprint>& fp, const MatcherOptions& matcher,
                              double process_bytes);
// Per image of g.MatchedIn(), the share of its cells that can take points
// (EstimateGroupMemory's cell_shares): a footprint group matches its tile
// and the merge keeps what it matched there, so each image takes points
// where its footprint (7 x 7 samples) lies in the tile, and 1 without a
// tile or a footprint; a view, never a reference, 0.
std::vector<double> CellShares(const ImageGroup& g, const std::vector<Footprint>& fp);
// The plan's options and matcher say what a group may use.
bool Fits(const Block& block, const std::vector<int>& ids, const GroupingPlan& plan);
bool Fits(const Block& block, const ImageGroup& g, const std::vector<Footprint>& fp,
          const GroupingPlan& plan);

Eigen::Vector2d MeanCenter(const std::vector<Footprint>& fp, const std::vector<int>& ids);

// Share of image i's footprint that image j sees (7 x 7 samples, as
// SelectViews counts views); 1 when either has no footprint, since nothing
// then says they do not overlap.
double OverlapShare(const std::vector<Footprint>& fp, int i, int j);

// Images of `ids` that overlap fewer than min_image_num - 1 others of
// `matched_in` (ImageGroup::MatchedIn: ids and the group's views).
std::vector<int> ShortOfViews(const std::vector<Footprint>& fp, const std::vector<int>& ids,
                              int min_image_num, const std::vector<int>& matched_in);

// Strip groups: up to strip_views images of other strips per group, as
// views only (GroupingOptions::strip_views).
void AddStripViews(const Block& block, const GroupingOptions& o, const std::vector<Footprint>& fp,
                   GroupingPlan* plan);

// Each image of `images` joins the group that sees most of its footprint:
// as one of its images while the group has room (max_images, the budget)
// and `as_image` allows it, else as a view. Returns those that fit nowhere.
std::vector<int> JoinBestGroup(const Block& block, const std::vector<Footprint>& fp,
                               const std::vector<int>& images, const std::vector<bool>& as_image,
                               GroupingPlan* plan);

// Strip groups under `smallest` images take, as images, those of other
// groups that see most of their ground, while they fit.
void TopUpSmallGroups(const Block& block, const std::vector<Footprint>& fp, size_t smallest,
                      GroupingPlan* plan);
// Views from beyond each group until some pair of the images it matches in
// meets at its images' mean footprint centre at 2 max_angle_deg or more (PatchEngine's
// WideEnough for the larger adaptive sizes).
void AddAngleViews(const Block& block, const std::vector<Footprint>& fp, GroupingPlan* plan);

// Largest angle, degrees, between the rays from `x` (local frame) to two
// of the cameras of `ids`, below view_angle_deg.
double SpanDeg(const Block& block, const std::vector<int>& ids, const Eigen::Vector3d& x,
               double view_angle_deg);

}  // namespace sapmvs

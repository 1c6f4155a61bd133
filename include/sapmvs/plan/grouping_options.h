#pragma once
// The planner's options (GroupingOptions) and their description, apart from
// the planner (grouping.h). The level the groups are matched at and the
// views a patch needs are the matcher's (MatcherOptions), which PlanGroups
// takes beside these.
#include <string>

#include "sapmvs/util/option_spec.h"

namespace sapmvs {

enum class GroupingStrategy { kStrip, kFootprint };
std::string ToString(GroupingStrategy s);
// "strip" or "footprint"; throws sapmvs::Error naming the text and the
// expected values otherwise.
GroupingStrategy ParseGroupingStrategy(const std::string& text);
inline void ParseOptionValue(const std::string& text, GroupingStrategy* strategy) {
  *strategy = ParseGroupingStrategy(text);
}

struct GroupingOptions {
  // Footprint: each group owns a tile of ground and takes the images that
  // see it best, so the group that owns a piece of ground can match it. On
  // a hand-flown 75-image flight (Caliterra, groups matching their own
  // ground) strip groups covered 81.9 % of the ground all runs covered,
  // footprint groups 93.3 %: a strip group at the block's edge owns ground
  // that its images see only at their borders.
  GroupingStrategy strategy = GroupingStrategy::kFootprint;
  // Most images per group, >= 2. On Caliterra (footprint groups, 3 extra
  // views) 6 covered 94.7 % of the ground all runs covered in 87 s, 8
  // covered 96.1 % in 109 s (PMVS2 96.3 %, 552 s): a point at a tile's
  // fringe or on a tree's rim needs more references than views.
  int max_images = 8;
  // Bytes the process's estimated peak while it matches one group must fit
  // in (GroupMemory::Total: what it held before, and the group's host side).
  // A GPU's own memory is the device estimate, which this does not bound.
  double memory_budget = 8.0 * (1ull << 30);
  // Footprint strategy: tile side as a share of the median image footprint's
  // shorter side on the ground, (0, 4]. Smaller tiles give more groups, each
  // with views chosen for a smaller area.
  double tile_size = 1.0;
  // Footprint strategy: images are added to a tile's group until every point
  // of the tile is seen by this many of them (or max_images is reached),
  // >= 2.
  int tile_views = 4;
  // Footprint strategy: each group also takes up to this many images as views
  // only, those that bring most of its tile's points towards tile_views +
  // tile_extra_views views: patches are matched in them, never referenced
  // there. On Caliterra (6 images per group) 3 raised the ground covered
  // from 93.1 to 94.7 % for 5 % more time; more added nothing. >= 0.
  int tile_extra_views = 3;
  // Strip strategy: each group also takes up to this many images of other
  // strips that see its ground, as views only: its patches are matched in
  // them, but no seed, patch or point has one as its reference, so the work
  // and the merge stay the paper's runs. A run alone sees the ground near a
  // strip's ends and edges in fewer than min_image_num images. >= 0 (0 = the
  // paper's runs alone).
  int strip_views = 2;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
  // "" or the first failing condition as "what was expected (name = value)".
  std::string Problem() const;
};

template <class F>
void VisitFields(GroupingOptions& o, F&& f) {
  const char* s = "Grouping";
  f(Field(o.strategy, "strategy")
        .Flag("--strategy")
        .In(s)
        .Help("strip (the paper: runs along flight strips) or footprint (ground tiles)"));
  f(Field(o.max_images, "max_images")
        .Flag("--max-images")
        .In(s)
        .Unit("images")
        .Range(AtLeast(2))
        .Help("Most images per group"));
  f(Field(o.memory_budget, "memory_budget")
        .Flag("--memory-budget")
        .In(s)
        .Unit("bytes")
        .Range(Above(0))
        .Style(FlagStyle::kByteSize)
        .Help("Memory the process may use while it matches one group: bytes, or 512M, 8G, 1.5G"));
  f(Field(o.tile_size, "tile_size")
        .Flag("--tile-size")
        .In(s)
        .Unit("footprints")
        .Range(Interval(0, 4, true, false))
        .Help("footprint: tile side, in median footprint shorter sides (tiles of at least 64 px "
              "and at most 100,000 of them)"));
  f(Field(o.tile_views, "tile_views")
        .Flag("--tile-views")
        .In(s)
        .Unit("images")
        .Range(AtLeast(2))
        .Help("footprint: images a tile's points should be seen in"));
  f(Field(o.tile_extra_views, "tile_extra_views")
        .Flag("--tile-extra-views")
        .In(s)
        .Unit("images")
        .Range(AtLeast(0))
        .Help("footprint: images each group also matches in as views only, those that add most "
              "views to its tile"));
  f(Field(o.strip_views, "strip_views")
        .Flag("--strip-views")
        .In(s)
        .Unit("images")
        .Range(AtLeast(0))
        .Help("strip: images of other strips each group matches in as views only, most "
              "overlap first (0 = the paper's runs alone)"));
}

}  // namespace sapmvs

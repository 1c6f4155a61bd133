#include "sapmvs/plan/grouping.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <random>
#include <set>

#include "plan/grouping_internal.h"
#include "plan/strip_detection.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/simulate/simulate.h"
#include "sapmvs/util/error.h"
#include "simulate/sim_presets.h"
#include "test_util.h"

namespace sapmvs {
namespace {

// Strip grouping's options: the tests here are of it, and the default
// strategy is footprint.
GroupingOptions StripOptions() {
  GroupingOptions o;
  o.strategy = GroupingStrategy::kStrip;
  o.max_images = 6;  // the paper's groups
  return o;
}

// The cameras `sapmvs simulate --preset NAME` renders, as a block without
// images (grouping never reads pixels). The simulator's mean ground is local
// z = 0, i.e. world z = the offset's.
struct SimBlock {
  Block block;
  std::vector<int> strip_of;  // the simulator's strip per image
};

SimBlock MakeSimBlock(const std::string& preset, bool cross_strip = false,
                      const std::vector<int>& keep_strips = {}) {
  const sim::Preset p = sim::FindPreset(preset);
  const sim::FlightPlan plan =
      sim::PlanFlight(p, p.camera, cross_strip, p.flight.exposure, /*seed=*/1);
  const Intrinsics k = Intrinsics::FromFocalAndPixel(p.camera.focal_mm, p.camera.pixel_um,
                                                     p.camera.width, p.camera.height);
  const Eigen::Vector3d offset = sim::WorldOffset(plan.scene_width, plan.scene_height);
  SimBlock s;
  s.block.source = "sim/" + preset;
  s.block.format = "sim";
  for (const PlannedImage& im : plan.images) {
    if (!keep_strips.empty() &&
        std::find(keep_strips.begin(), keep_strips.end(), im.strip) == keep_strips.end())
      continue;
    BlockImage bi;
    bi.name = im.name;
    bi.camera_name = "camera";
    bi.camera = Camera::FromAngles(k, im.center + offset, im.omega, im.phi, im.kappa,
                                   AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
    s.block.images.push_back(bi);
    s.strip_of.push_back(im.strip);
  }
  s.block.ground_height = offset.z();
  s.block.origin = ChooseLocalOrigin(s.block.images);
  return s;
}

std::vector<size_t> Sizes(const GroupingPlan& plan) {
  std::vector<size_t> sizes;
  for (const ImageGroup& g : plan.groups) sizes.push_back(g.images.size());
  return sizes;
}

// Strips as name sequences, sorted, so that blocks listing the same images in
// different orders compare equal.
std::vector<std::vector<std::string>> StripNames(const Block& block,
                                                 const std::vector<std::vector<int>>& strips) {
  std::vector<std::vector<std::string>> out;
  for (const auto& s : strips) {
    out.emplace_back();
    for (const int i : s) out.back().push_back(block.images[i].name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The simulator's strips, in its (flight) order.
std::vector<std::vector<int>> TrueStrips(const SimBlock& s) {
  std::map<int, std::vector<int>> by;
  for (size_t i = 0; i < s.strip_of.size(); ++i) by[s.strip_of[i]].push_back(static_cast<int>(i));
  std::vector<std::vector<int>> out;
  for (auto& [strip, ids] : by) out.push_back(ids);
  return out;
}

TEST(GroupingTable3, CampusStripStrategyMatchesThePaper) {
  const SimBlock s = MakeSimBlock("campus");
  ASSERT_EQ(s.block.images.size(), 67u);
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  EXPECT_EQ(plan.strategy, GroupingStrategy::kStrip);
  EXPECT_EQ(plan.strips, TrueStrips(s));
  EXPECT_EQ(Sizes(plan), (std::vector<size_t>{6, 6, 4, 6, 6, 5, 6, 6, 6, 6, 6, 4}));
  // Table 3: the groups are the images 0..66 cut in order.
  std::vector<int> all;
  for (const ImageGroup& g : plan.groups) {
    for (size_t k = 1; k < g.images.size(); ++k) EXPECT_EQ(g.images[k], g.images[k - 1] + 1);
    all.insert(all.end(), g.images.begin(), g.images.end());
    EXPECT_GE(g.strip, 0);
    EXPECT_EQ(s.strip_of[g.images[0]], g.strip);
    EXPECT_GT(g.memory.device_bytes, 0);
    EXPECT_GT(g.memory.host_bytes, 0);
  }
  std::vector<int> expected(67);
  std::iota(expected.begin(), expected.end(), 0);
  EXPECT_EQ(all, expected);
  EXPECT_TRUE(plan.ungrouped.empty());
}

// Each strip run also takes the images of other strips that see most of its
// ground, as views only: never one of its own strip or group, at most
// strip_views, from the neighbouring strips (campus's side overlap reaches no
// further), best first; 0 gives the paper's runs alone. The runs themselves
// stay Table 3's.
TEST(GroupingStrips, StripViewsComeFromTheNeighbouringStrips) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  ASSERT_EQ(o.strip_views, 2);
  const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
  EXPECT_EQ(Sizes(plan), (std::vector<size_t>{6, 6, 4, 6, 6, 5, 6, 6, 6, 6, 6, 4}));
  for (const ImageGroup& g : plan.groups) {
    EXPECT_EQ(g.views.size(), 2u) << "group of strip " << g.strip;
    for (const int v : g.views) {
      EXPECT_NE(s.strip_of[v], g.strip);
      EXPECT_EQ(std::abs(s.strip_of[v] - g.strip), 1) << s.block.images[v].name;
      EXPECT_EQ(std::count(g.images.begin(), g.images.end(), v), 0);
    }
    EXPECT_EQ(std::set<int>(g.views.begin(), g.views.end()).size(), g.views.size());
  }
  GroupingOptions more = o;
  more.strip_views = 5;
  const GroupingPlan wide = PlanGroups(s.block, more, MatcherOptions{});
  for (size_t g = 0; g < wide.groups.size(); ++g) {
    // The same ranking: the first two of five are the two.
    ASSERT_GE(wide.groups[g].views.size(), 2u);
    EXPECT_EQ(std::vector<int>(wide.groups[g].views.begin(), wide.groups[g].views.begin() + 2),
              plan.groups[g].views);
    EXPECT_LE(wide.groups[g].views.size(), 5u);
  }
  // Without them, a group takes views only where its own images do not
  // span twice max_angle_deg (10) at their ground, and then as many as do.
  const std::vector<Footprint> fp = Footprints(s.block, EstimateBlockGeometry(s.block));
  auto span = [&](const ImageGroup& g, const std::vector<int>& ids) {
    const Eigen::Vector2d c = MeanCenter(fp, g.images);
    return SpanDeg(s.block, ids, Eigen::Vector3d(c.x(), c.y(), fp[g.images[0]].scene_z), 60);
  };
  GroupingOptions none = o;
  none.strip_views = 0;
  for (const ImageGroup& g : PlanGroups(s.block, none, MatcherOptions{}).groups) {
    EXPECT_EQ(g.views.empty(), span(g, g.images) >= 20) << span(g, g.images);
    EXPECT_GE(span(g, g.MatchedIn()), 20);
  }
  // The footprint strategy chooses its images per tile; its views are the
  // images no tile chose and those that widen the angle.
  GroupingOptions tiles = o;
  tiles.strategy = GroupingStrategy::kFootprint;
  for (const ImageGroup& g : PlanGroups(s.block, tiles, MatcherOptions{}).groups)
    EXPECT_GE(span(g, g.MatchedIn()), 20);
}

// A view-only image counts in the memory budget, though less than an image
// of the group (it takes no points): under a budget that holds 6 of campus's
// (equal) images, a run of 6 takes no views, and a shorter one takes views
// until one more would not fit.
TEST(GroupingStrips, StripViewsStayWithinTheBudget) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  for (const int fit : {6, 7}) {
    std::vector<int> ids(fit);
    std::iota(ids.begin(), ids.end(), 0);
    o.memory_budget = EstimateGroupMemory(s.block, ids, 1).Total() + 1;
    int short_runs_with_views = 0;
    for (const ImageGroup& g : PlanGroups(s.block, o, MatcherOptions{}).groups) {
      EXPECT_LE(g.memory.Total(), o.memory_budget);
      if (static_cast<int>(g.images.size()) == fit) {
        EXPECT_TRUE(g.views.empty());
      }
      if (static_cast<int>(g.images.size()) >= fit) continue;
      short_runs_with_views += !g.views.empty();
      if (g.views.size() >= 2) continue;
      // One more view (any image of the block, all of campus's being the
      // same size) would not have fitted.
      std::vector<int> with = g.MatchedIn();
      with.push_back(with.front());
      std::vector<double> shares(g.images.size(), 1.0);
      shares.resize(with.size(), 0.0);
      MatcherOptions level1;
      level1.level = 1;
      EXPECT_GT(EstimateGroupMemory(s.block, with, level1, shares).Total() + g.memory.process_bytes,
                o.memory_budget);
    }
    EXPECT_GT(short_runs_with_views, 0) << "budget for " << fit << " images";
  }
}

// A view costs its pixels but no cells; an image of a footprint group only
// the cells it sees of the tile (cell_shares).
TEST(GroupingMemory, ViewsAndGroundOutsideTheTileTakeNoPoints) {
  const SimBlock s = MakeSimBlock("campus");
  MatcherOptions m;
  const GroupMemory refs = EstimateGroupMemory(s.block, {0, 1}, m);
  EXPECT_DOUBLE_EQ(EstimateGroupMemory(s.block, {0, 1}, m, {1.0, 1.0}).host_bytes, refs.host_bytes);
  const GroupMemory view = EstimateGroupMemory(s.block, {0, 1}, m, {1.0, 0.0});
  const GroupMemory half = EstimateGroupMemory(s.block, {0, 1}, m, {1.0, 0.5});
  EXPECT_LT(view.host_bytes, refs.host_bytes);
  EXPECT_DOUBLE_EQ(half.host_bytes - view.host_bytes, 0.5 * (refs.host_bytes - view.host_bytes));
  // 486 x 324 pixels at level 1.
  EXPECT_DOUBLE_EQ(refs.host_bytes - view.host_bytes,
                   MatcherMemory().host_bytes_per_point_pixel * 486 * 324);
  // The device holds a view's grey as it holds any image's.
  EXPECT_DOUBLE_EQ(view.device_bytes, refs.device_bytes);
  // What the budget bounds is the process: the device's own memory apart.
  EXPECT_DOUBLE_EQ(refs.Total(), refs.host_bytes + refs.process_bytes);
  EXPECT_THROW(EstimateGroupMemory(s.block, {0, 1}, m, {1.0}), Error);
  EXPECT_THROW(EstimateGroupMemory(s.block, {0, 1}, m, {1.0, 1.5}), Error);
  EXPECT_THROW(EstimateGroupMemory(s.block, {0, 1}, m, {1.0, -0.1}), Error);
  EXPECT_THROW(EstimateGroupMemory(s.block, {0, 1}, m, {1.0, std::nan("")}), Error);
}

// `run` matches what PlanGroups returns; a block that fits one group is not
// split, whatever the strategy, since splitting it would only lose views.
TEST(GroupingSingle, ABlockThatFitsIsOneGroupAndALargerOneIsSplit) {
  const SimBlock s = MakeSimBlock("tiny");
  ASSERT_EQ(s.block.images.size(), 4u);
  for (const GroupingStrategy strategy : {GroupingStrategy::kStrip, GroupingStrategy::kFootprint}) {
    GroupingOptions o = StripOptions();
    o.strategy = strategy;
    const GroupingPlan one = PlanGroups(s.block, o, MatcherOptions{});
    EXPECT_TRUE(one.single_group);
    ASSERT_EQ(one.groups.size(), 1u);
    EXPECT_EQ(one.groups[0].images, (std::vector<int>{0, 1, 2, 3}));
    EXPECT_GT(one.groups[0].memory.Total(), 0);

    o.max_images = 3;  // fewer than the block's images
    const GroupingPlan split = PlanGroups(s.block, o, MatcherOptions{});
    EXPECT_FALSE(split.single_group);
    EXPECT_GT(split.groups.size(), 1u);

    o.max_images = 6;
    // Three images fit, the whole block does not.
    o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2}, MatcherOptions{}).Total();
    const GroupingPlan budget = PlanGroups(s.block, o, MatcherOptions{});
    EXPECT_FALSE(budget.single_group);
    for (const ImageGroup& g : budget.groups) EXPECT_LE(g.memory.Total(), o.memory_budget);
  }
}

TEST(GroupingTable3, GroupCentresLieOnTheirImagesFootprints) {
  const SimBlock s = MakeSimBlock("campus");
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  for (const ImageGroup& g : plan.groups) {
    // Nadir images: the footprint centre is near the camera's XY.
    Eigen::Vector2d cams = Eigen::Vector2d::Zero();
    for (const int i : g.images)
      cams += (s.block.images[i].camera.center() - s.block.origin).head<2>();
    cams /= static_cast<double>(g.images.size());
    EXPECT_LT((g.center - cams).norm(), 0.05 * 700) << g.center.transpose();
  }
}

TEST(GroupingStrips, CrossStripIsItsOwnStrip) {
  const SimBlock s = MakeSimBlock("campus", /*cross_strip=*/true);
  ASSERT_GT(s.block.images.size(), 67u);
  const std::vector<std::vector<int>> strips = DetectStrips(s.block).strips;
  EXPECT_EQ(strips, TrueStrips(s));
  ASSERT_EQ(strips.size(), 5u);
  EXPECT_EQ(strips[4].size(), s.block.images.size() - 67);
}

TEST(GroupingStrips, ShuffledOrderGivesTheSameStripsInFlightOrder) {
  SimBlock s = MakeSimBlock("campus", /*cross_strip=*/true);
  const auto expected = StripNames(s.block, TrueStrips(s));
  std::mt19937 rng(7);
  std::shuffle(s.block.images.begin(), s.block.images.end(), rng);
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  EXPECT_EQ(StripNames(s.block, plan.strips), expected);
  // Same cut as in flight order: 6+6+4, 6+6+5, 6+6+6, 6+6+4 and the cross strip's.
  std::vector<size_t> sizes = Sizes(plan);
  std::sort(sizes.begin(), sizes.end());
  SimBlock ordered = MakeSimBlock("campus", true);
  std::vector<size_t> want = Sizes(PlanGroups(ordered.block, StripOptions(), MatcherOptions{}));
  std::sort(want.begin(), want.end());
  EXPECT_EQ(sizes, want);
}

TEST(GroupingStrips, SingleStrip) {
  const SimBlock s = MakeSimBlock("campus", false, {2});
  ASSERT_EQ(s.block.images.size(), 18u);
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  ASSERT_EQ(plan.strips.size(), 1u);
  std::vector<int> all(18);
  std::iota(all.begin(), all.end(), 0);
  EXPECT_EQ(plan.strips[0], all);
  EXPECT_EQ(Sizes(plan), (std::vector<size_t>{6, 6, 6}));
}

TEST(GroupingStrips, StripFlownBackwardsKeepsFlightOrder) {
  // Strip 1 flies -X: its images in flight order have decreasing X.
  const SimBlock s = MakeSimBlock("campus", false, {1});
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  ASSERT_EQ(plan.strips.size(), 1u);
  const auto& strip = plan.strips[0];
  for (size_t k = 1; k < strip.size(); ++k) {
    EXPECT_EQ(strip[k], strip[k - 1] + 1);
    EXPECT_LT(s.block.images[strip[k]].camera.center().x(),
              s.block.images[strip[k - 1]].camera.center().x());
  }
  // Shuffled, the image x axis (kappa 180: -X) still gives the flight order.
  SimBlock shuffled = s;
  std::mt19937 rng(3);
  std::shuffle(shuffled.block.images.begin(), shuffled.block.images.end(), rng);
  const auto strips = PlanGroups(shuffled.block, StripOptions(), MatcherOptions{}).strips;
  EXPECT_EQ(StripNames(shuffled.block, strips), StripNames(s.block, plan.strips));
}

TEST(GroupingStrips, ShortRemainderMovesTheCutsBack) {
  // 13 images: 6 + 6 + 1 would leave an image with nothing to match, and
  // 6 + 5 + 2 a group under the paper's smallest (4).
  SimBlock s = MakeSimBlock("campus", false, {0});
  s.block.images.resize(13);
  const GroupingPlan plan13 = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  EXPECT_EQ(Sizes(plan13), (std::vector<size_t>{5, 4, 4}));
  std::vector<int> all;
  for (const ImageGroup& g : plan13.groups) {
    EXPECT_TRUE(g.short_of_views.empty());
    all.insert(all.end(), g.images.begin(), g.images.end());
  }
  EXPECT_EQ(all, plan13.strips[0]);  // each image once, in flight order
  MatcherOptions pairs;
  pairs.min_image_num = 2;
  EXPECT_EQ(Sizes(PlanGroups(s.block, StripOptions(), pairs)), (std::vector<size_t>{5, 4, 4}));
  // 14 -> 6 + 4 + 4: the full runs first, as the paper's.
  s = MakeSimBlock("campus", false, {0});
  s.block.images.resize(14);
  EXPECT_EQ(Sizes(PlanGroups(s.block, StripOptions(), MatcherOptions{})),
            (std::vector<size_t>{6, 4, 4}));
  // Groups of 2 cannot have 4: a single image left shares the one before.
  GroupingOptions two = StripOptions();
  two.max_images = 2;
  s.block.images.resize(5);
  const GroupingPlan plan = PlanGroups(s.block, two, MatcherOptions{});
  ASSERT_EQ(plan.groups.size(), 3u);
  EXPECT_EQ(plan.groups[2].images, (std::vector<int>{3, 4}));  // shares image 3
}

TEST(GroupingStrips, LoneImageJoinsTheNearestGroup) {
  SimBlock s = MakeSimBlock("campus", false, {0});
  // A stray exposure turned by 90 deg over image 11. Its own group (6..11)
  // is full, and the 4 (12..15) is nearer than the first 6.
  BlockImage stray = s.block.images[11];
  stray.name = "STRAY";
  const Camera& c = stray.camera;
  stray.camera = Camera::FromAngles(c.intrinsics(), c.center(), 0, 0, 90,
                                    AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  s.block.images.push_back(stray);
  const GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  // Off the strip's line after its end: a stray, not a strip of its own.
  EXPECT_EQ(plan.strips.size(), 1u);
  ASSERT_EQ(plan.outliers.size(), 1u);
  EXPECT_EQ(plan.outliers[0].image, 16);
  EXPECT_EQ(plan.outliers[0].kind, OutlierKind::kStray);
  EXPECT_TRUE(plan.ungrouped.empty());
  int holder = -1;
  for (size_t g = 0; g < plan.groups.size(); ++g)
    for (const int i : plan.groups[g].images)
      if (i == 16) holder = static_cast<int>(g);
  EXPECT_EQ(holder, 2);
}

TEST(GroupingStrips, NoGroupUnderTheSmallestWhileOthersHaveImagesToLend) {
  // A strip of 7 at 6 per group: 6 + 1 cannot move its cuts back to 4 + 4,
  // and the run left (5 + 3, sharing one) is under the paper's smallest.
  SimBlock s = MakeSimBlock("campus", false, {0});
  s.block.images.resize(7);
  GroupingPlan plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  ASSERT_EQ(plan.groups.size(), 2u);
  for (const ImageGroup& g : plan.groups) {
    EXPECT_GE(g.images.size(), 4u);
    EXPECT_LE(g.images.size(), 6u);
  }
  // A short strip beside full groups: campus's strip 2 (18 images, 6 + 6 +
  // 6) and the first 3 images of strip 3. No group has room for those 3, so
  // they are a group, which takes an image of strip 2 that sees its ground.
  s = MakeSimBlock("campus", false, {2, 3});
  s.block.images.resize(21);
  plan = PlanGroups(s.block, StripOptions(), MatcherOptions{});
  ASSERT_EQ(plan.strips.size(), 2u);
  ASSERT_EQ(plan.strips[1].size(), 3u);
  ASSERT_EQ(plan.groups.size(), 4u);
  for (const ImageGroup& g : plan.groups) EXPECT_GE(g.images.size(), 4u);
  const std::vector<int>& short_group = plan.groups.back().images;
  EXPECT_EQ(std::count_if(short_group.begin(), short_group.end(), [](int i) { return i < 18; }), 1);
  EXPECT_TRUE(plan.ungrouped.empty());
}

// Ground points (local XY on the mean ground) and the images that see them.
struct GroundSample {
  Eigen::Vector2d xy;
  std::vector<int> seen_by;
};

std::vector<GroundSample> SampleGround(const Block& block, int n) {
  const BlockGeometry g = EstimateBlockGeometry(block);
  const Eigen::Vector2d lo = (g.extent_min - block.origin).head<2>();
  const Eigen::Vector2d hi = (g.extent_max - block.origin).head<2>();
  std::vector<GroundSample> out;
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < 2 * n; ++x) {
      GroundSample s;
      s.xy = lo + Eigen::Vector2d((x + 0.5) / (2 * n), (y + 0.5) / n).cwiseProduct(hi - lo);
      const Eigen::Vector3d p(s.xy.x() + block.origin.x(), s.xy.y() + block.origin.y(),
                              *block.ground_height);
      for (size_t i = 0; i < block.images.size(); ++i) {
        const Camera& cam = block.images[i].camera;
        if (cam.InImage(cam.Project(p))) s.seen_by.push_back(static_cast<int>(i));
      }
      out.push_back(std::move(s));
    }
  }
  return out;
}

int NearestGroup(const GroupingPlan& plan, const Eigen::Vector2d& xy) {
  int best = -1;
  for (size_t g = 0; g < plan.groups.size(); ++g)
    if (best < 0 || (plan.groups[g].center - xy).norm() < (plan.groups[best].center - xy).norm())
      best = static_cast<int>(g);
  return best;
}

TEST(GroupingFootprint, EveryGroundPointSeenTwiceIsOwnedByAGroupThatSeesIt) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.strategy = GroupingStrategy::kFootprint;
  const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
  ASSERT_FALSE(plan.groups.empty());
  int matchable = 0, in_tile = 0, owner_sees = 0;
  for (const GroundSample& p : SampleGround(s.block, 40)) {
    if (p.seen_by.size() < 2) continue;
    ++matchable;
    bool tiled = false;
    for (const ImageGroup& g : plan.groups)
      tiled |=
          (p.xy.array() >= g.tile_min.array()).all() && (p.xy.array() <= g.tile_max.array()).all();
    in_tile += tiled;
    // The merge's owner (nearest centre) must have >= 2 views of the point.
    const ImageGroup& owner = plan.groups[NearestGroup(plan, p.xy)];
    int views = 0;
    for (const int i : owner.images) views += std::count(p.seen_by.begin(), p.seen_by.end(), i) > 0;
    owner_sees += views >= 2;
  }
  ASSERT_GT(matchable, 1000);
  EXPECT_EQ(in_tile, matchable);
  EXPECT_EQ(owner_sees, matchable) << owner_sees << " of " << matchable;
}

// Footprint tiles need ground under the images: a facade block (the
// default strategy) is grouped as the strip strategy groups it, every image
// in a group.
TEST(GroupingFootprint, ABlockThatDoesNotLookDownIsGroupedAsStrips) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const Block block = ReadBlock(test::HerzJesu());
  const BlockGeometry geometry = EstimateBlockGeometry(block);
  ASSERT_FALSE(geometry.aerial);
  GroupingOptions o;
  ASSERT_EQ(o.strategy, GroupingStrategy::kFootprint);
  o.max_images = 4;
  const GroupingPlan plan = PlanGroups(block, o, MatcherOptions{}, &geometry);
  EXPECT_EQ(plan.strategy, GroupingStrategy::kStrip);
  EXPECT_GE(plan.groups.size(), 2u);
  std::set<int> grouped;
  for (const ImageGroup& g : plan.groups) grouped.insert(g.images.begin(), g.images.end());
  EXPECT_EQ(grouped.size(), block.images.size());
  EXPECT_TRUE(plan.ungrouped.empty());
}

TEST(GroupingFootprint, NoTwoGroupsMatchTheSameImages) {
  // Tiles that pick the same images are one group: matching the same images
  // twice only makes the same cloud twice.
  for (const char* preset : {"small", "campus"}) {
    const SimBlock s = MakeSimBlock(preset);
    GroupingOptions o = StripOptions();
    o.strategy = GroupingStrategy::kFootprint;
    o.tile_size = 0.5;  // small tiles: neighbours often choose alike
    const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
    std::set<std::vector<int>> sets;
    for (const ImageGroup& g : plan.groups) {
      std::vector<int> ids = g.images;
      std::sort(ids.begin(), ids.end());
      EXPECT_TRUE(sets.insert(ids).second) << preset << ": images matched twice";
    }
  }
}

TEST(GroupingFootprint, NoSmallGroupWhoseNeighboursCanTakeItsGround) {
  // Tiles of half a footprint leave slivers at the block's edges that two
  // or three images reach. Such a group stays only where some of its ground
  // would go (to the nearest other centre) to a group without all of its
  // images. Measured: 8 such groups on `small` with none taken, 3 after.
  for (const char* preset : {"small", "campus"}) {
    const SimBlock s = MakeSimBlock(preset);
    GroupingOptions o = StripOptions();
    o.strategy = GroupingStrategy::kFootprint;
    o.tile_size = 0.5;
    const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
    int small = 0;
    for (size_t k = 0; k < plan.groups.size(); ++k) {
      const ImageGroup& g = plan.groups[k];
      if (g.images.size() >= 4) continue;
      ++small;
      std::vector<int> mine = g.images;
      std::sort(mine.begin(), mine.end());
      bool lacking = false;
      for (int sy = 0; sy < 16; ++sy) {
        for (int sx = 0; sx < 16; ++sx) {
          const Eigen::Vector2d p = g.tile_min + Eigen::Vector2d((sx + 0.5) / 16, (sy + 0.5) / 16)
                                                     .cwiseProduct(g.tile_max - g.tile_min);
          int to = -1;
          for (size_t j = 0; j < plan.groups.size(); ++j) {
            if (j != k && (to < 0 || (plan.groups[j].center - p).norm() <
                                         (plan.groups[to].center - p).norm()))
              to = static_cast<int>(j);
          }
          std::vector<int> theirs = plan.groups[to].images;
          std::sort(theirs.begin(), theirs.end());
          lacking |= !std::includes(theirs.begin(), theirs.end(), mine.begin(), mine.end());
        }
      }
      EXPECT_TRUE(lacking) << preset << ": a group of " << g.images.size()
                           << " images whose neighbours hold them all";
    }
    if (std::string(preset) == "small") {
      EXPECT_GT(small, 0) << "no sliver to test on";
    }
  }
}

TEST(GroupingFootprint, GroupsRespectMaxImagesAndTheBudget) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.strategy = GroupingStrategy::kFootprint;
  o.max_images = 8;
  o.tile_views = 8;
  // Room for 3 images of the block that take points on their whole
  // footprints, not 4; a footprint group's images take them on its tile only.
  o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2}, MatcherOptions{}).Total() + 1;
  ASSERT_GT(EstimateGroupMemory(s.block, {0, 1, 2, 3}, MatcherOptions{}).Total(), o.memory_budget);
  const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
  ASSERT_FALSE(plan.groups.empty());
  size_t largest = 0;
  for (const ImageGroup& g : plan.groups) {
    largest = std::max(largest, g.images.size());
    EXPECT_GE(g.images.size(), 2u);
    EXPECT_LE(g.memory.Total(), o.memory_budget);
    EXPECT_EQ(g.strip, -1);
    EXPECT_TRUE((g.center.array() > g.tile_min.array()).all());
    EXPECT_TRUE((g.center.array() < g.tile_max.array()).all());
  }
  EXPECT_GT(largest, 3u);
  // The budget still binds: without it, groups are larger.
  o.memory_budget = 8.0 * (1ull << 30);
  size_t unbound = 0;
  for (const ImageGroup& g : PlanGroups(s.block, o, MatcherOptions{}).groups) {
    EXPECT_LE(g.images.size(), 8u);
    unbound = std::max(unbound, g.images.size());
  }
  EXPECT_GT(unbound, largest);
}

TEST(GroupingFootprint, ExtraViewsSeeTheTileAndAreNoneOfItsImages) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.strategy = GroupingStrategy::kFootprint;
  o.tile_extra_views = 0;
  const GroupingPlan without = PlanGroups(s.block, o, MatcherOptions{});
  o.tile_extra_views = 3;
  const GroupingPlan with = PlanGroups(s.block, o, MatcherOptions{});
  ASSERT_EQ(with.groups.size(), without.groups.size());
  const std::vector<Footprint> fp = Footprints(s.block, EstimateBlockGeometry(s.block));
  long added = 0;
  for (size_t g = 0; g < with.groups.size(); ++g) {
    const ImageGroup& a = with.groups[g];
    added += static_cast<long>(a.views.size()) - static_cast<long>(without.groups[g].views.size());
    for (const int v : a.views) {
      EXPECT_EQ(std::count(a.images.begin(), a.images.end(), v), 0) << "group " << g + 1;
      const Eigen::Vector2d c = (a.tile_min + a.tile_max) / 2;
      const Eigen::Vector2d h = (a.tile_max - a.tile_min) / 2;
      bool sees = false;
      for (int k = 0; k < 9; ++k)
        sees |= fp[v].Contains(c + Eigen::Vector2d((k % 3 - 1) * h.x(), (k / 3 - 1) * h.y()));
      EXPECT_TRUE(sees) << "group " << g + 1 << ": view " << v << " sees none of the tile";
    }
  }
  EXPECT_GE(added, static_cast<long>(with.groups.size()));
}

TEST(GroupingFootprint, SideOverlapBringsImagesOfNeighbouringStrips) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.strategy = GroupingStrategy::kFootprint;
  const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
  int mixed = 0;
  for (const ImageGroup& g : plan.groups) {
    std::set<int> strips;
    for (const int i : g.images) strips.insert(s.strip_of[i]);
    mixed += strips.size() >= 2;
  }
  EXPECT_GE(mixed, static_cast<int>(plan.groups.size()) / 3)
      << mixed << " of " << plan.groups.size();
}

TEST(GroupingMemory, GrowsLinearlyWithImages) {
  const SimBlock s = MakeSimBlock("campus");
  const GroupMemory none = EstimateGroupMemory(s.block, {}, 1);
  const GroupMemory one = EstimateGroupMemory(s.block, {0}, 1);
  const GroupMemory two = EstimateGroupMemory(s.block, {0, 1}, 1);
  const GroupMemory six = EstimateGroupMemory(s.block, {0, 1, 2, 3, 4, 5}, 1);
  const double device_per_image = one.device_bytes - none.device_bytes;
  EXPECT_GT(device_per_image, 0);
  EXPECT_DOUBLE_EQ(six.device_bytes - none.device_bytes, 6 * device_per_image);
  // The loading peak is the largest image's, so host grows from one image on.
  const double host_per_image = two.host_bytes - one.host_bytes;
  EXPECT_GT(host_per_image, 0);
  EXPECT_DOUBLE_EQ(six.host_bytes - one.host_bytes, 5 * host_per_image);
  // A 972 x 648 image at level 1: 486 x 324 float32 grey.
  EXPECT_DOUBLE_EQ(device_per_image, 4.0 * 486 * 324);
}

TEST(GroupingMemory, GrowsFourTimesPerLevelTowardsFullResolution) {
  const SimBlock s = MakeSimBlock("campus");
  auto per_image = [&](int level) {
    const GroupMemory one = EstimateGroupMemory(s.block, {0}, level);
    const GroupMemory two = EstimateGroupMemory(s.block, {0, 1}, level);
    return std::make_pair(two.device_bytes - one.device_bytes, two.host_bytes - one.host_bytes);
  };
  const auto l0 = per_image(0), l1 = per_image(1), l2 = per_image(2);
  // 972 x 648 halves exactly to 486 x 324; the 2 x 2 cell grid of 243 x 162
  // pixels rounds up, so level 2 is within 1 %.
  EXPECT_DOUBLE_EQ(l0.first, 4 * l1.first);
  EXPECT_DOUBLE_EQ(l0.second, 4 * l1.second);
  EXPECT_DOUBLE_EQ(l1.first, 4 * l2.first);
  EXPECT_NEAR(l1.second, 4 * l2.second, 0.01 * l1.second);
}

TEST(GroupingMemory, TinyBudgetIsAClearError) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.memory_budget = 1 << 20;
  try {
    PlanGroups(s.block, o, MatcherOptions{});
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("memory budget 1 MiB is too small"), std::string::npos) << what;
    // min_image_num (3) images: the fewest a group can match.
    EXPECT_NE(what.find("3 images"), std::string::npos) << what;
    EXPECT_NE(what.find("level 1"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_THROW(EstimateGroupMemory(s.block, {0, 67}, 1), Error);
  EXPECT_THROW(EstimateGroupMemory(s.block, {0}, 7), Error);
}

TEST(GroupingMemory, BudgetShortensTheRunsOfAStrip) {
  const SimBlock s = MakeSimBlock("campus");
  GroupingOptions o = StripOptions();
  o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2, 3}, 1).Total() + 1;
  const GroupingPlan plan = PlanGroups(s.block, o, MatcherOptions{});
  // 16 -> 4+4+4+4, 17 -> 4+4+4+3+2, 18 -> 4+4+4+4+2, 16 -> 4+4+4+4, each
  // run of 2 taking the image before it (min_image_num 3), then each group
  // of 3 an image that sees its ground (the paper's smallest group is 4).
  EXPECT_EQ(Sizes(plan), std::vector<size_t>(18, 4));
  for (const ImageGroup& g : plan.groups) EXPECT_LE(g.memory.Total(), o.memory_budget);
}

TEST(GroupingMemory, BudgetBelowTheFewestImagesAGroupCanMatchIsAnError) {
  const SimBlock s = MakeSimBlock("campus");
  MatcherOptions m;
  m.min_image_num = 4;
  GroupingOptions o = StripOptions();
  // Three images fit, four do not: groups of three would match nothing.
  o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2}, m).Total() + 1;
  try {
    PlanGroups(s.block, o, m);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("4 images, the fewest a group can match (min_image_num 4)"),
              std::string::npos)
        << what;
  }
  o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2, 3}, m).Total() + 1;
  for (const ImageGroup& g : PlanGroups(s.block, o, m).groups) EXPECT_GE(g.images.size(), 4u);
}

TEST(GroupingMemory, TheProcessCountsInEveryGroupAndInTheBudget) {
  const SimBlock s = MakeSimBlock("campus");
  const double process = 300.0 * (1 << 20);
  // With what its first group adds to it for good.
  const double counted = process + MatcherMemory().runtime_warmup_bytes;
  EXPECT_GT(counted, process);
  GroupingOptions o = StripOptions();
  o.memory_budget = EstimateGroupMemory(s.block, {0, 1, 2, 3}, 1).Total() + counted + 1;
  const GroupingPlan with = PlanGroups(s.block, o, MatcherOptions{}, nullptr, process);
  EXPECT_EQ(with.process_bytes, counted);
  // The same runs as BudgetShortensTheRunsOfAStrip, whose budget is this one
  // less the process.
  EXPECT_EQ(Sizes(with), std::vector<size_t>(18, 4));
  for (const ImageGroup& g : with.groups) {
    EXPECT_EQ(g.memory.process_bytes, counted);
    // View-only images are loaded too, but take no points: strip groups'
    // images take them over their whole footprints.
    std::vector<double> shares(g.images.size(), 1.0);
    shares.resize(g.MatchedIn().size(), 0.0);
    MatcherOptions level1;
    level1.level = 1;
    EXPECT_DOUBLE_EQ(g.memory.Total(),
                     EstimateGroupMemory(s.block, g.MatchedIn(), level1, shares).Total() + counted);
    EXPECT_LE(g.memory.Total(), o.memory_budget);
  }
  // Without the process in the budget the groups would not have fitted.
  GroupingOptions tight = o;
  tight.memory_budget = o.memory_budget - counted;
  EXPECT_THROW(PlanGroups(s.block, tight, MatcherOptions{}, nullptr, 2 * process), Error);
  EXPECT_THROW(PlanGroups(s.block, o, MatcherOptions{}, nullptr, -1), Error);
}

TEST(GroupingOptions, DefaultsAreValidAndEveryBoundaryIsChecked) {
  EXPECT_TRUE(GroupingOptions{}.Check());
  EXPECT_EQ(GroupingOptions{}.Problem(), "");
  auto problem = [](auto set) {
    GroupingOptions o;
    set(o);
    return o.Problem();
  };
  EXPECT_NE(problem([](GroupingOptions& o) { o.max_images = 1; }).find("max_images = 1"),
            std::string::npos);
  EXPECT_EQ(problem([](GroupingOptions& o) { o.max_images = 2; }), "");
  EXPECT_NE(problem([](GroupingOptions& o) { o.memory_budget = 0; }).find("memory_budget"),
            std::string::npos);
  EXPECT_NE(problem([](GroupingOptions& o) { o.memory_budget = NAN; }).find("memory_budget"),
            std::string::npos);
  EXPECT_NE(problem([](GroupingOptions& o) { o.tile_size = 0; }).find("tile_size"),
            std::string::npos);
  EXPECT_NE(problem([](GroupingOptions& o) { o.tile_size = 4.5; }).find("tile_size"),
            std::string::npos);
  EXPECT_NE(problem([](GroupingOptions& o) { o.tile_views = 1; }).find("tile_views = 1"),
            std::string::npos);
  // Above max_images it only means "as many as fit".
  EXPECT_EQ(problem([](GroupingOptions& o) { o.tile_views = 7; }), "");
  GroupingOptions bad;
  bad.max_images = 0;
  EXPECT_FALSE(bad.Check());
  const SimBlock s = MakeSimBlock("tiny");
  EXPECT_THROW(PlanGroups(s.block, bad, MatcherOptions{}), Error);
}

TEST(GroupingPlan, TooFewImages) {
  SimBlock s = MakeSimBlock("tiny");
  s.block.images.resize(1);
  EXPECT_THROW(PlanGroups(s.block, StripOptions(), MatcherOptions{}), Error);
}

}  // namespace
}  // namespace sapmvs

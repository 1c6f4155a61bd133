// Strips and groups of blocks flown as people fly them: by hand, with a
// climb, turn photos, wandering headings and uneven spacing, listed out of
// order; and a grid flown with the same short spacing along and across.
// (The strategies' names are checked here too.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>

#include "plan/grouping_internal.h"
#include "plan/strip_detection.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Strip grouping's options, with the paper's groups of 6: the tests here
// are of it, and the default strategy is footprint.
GroupingOptions StripOptions() {
  GroupingOptions o;
  o.strategy = GroupingStrategy::kStrip;
  o.max_images = 6;
  return o;
}

// 1200 x 900 px at f = 1000 px: 62 x 48 deg, a small UAV's camera.
Intrinsics HandCamera() { return Intrinsics::FromFocalAndPixel(5.0, 5.0, 1200, 900); }

struct Flown {
  Block block;
  std::vector<std::vector<std::string>> strips;  // true strips, names in flight order
  std::set<std::string> climb, turns;            // the outliers by what they are
};

BlockImage Shot(const std::string& name, const Eigen::Vector3d& c, double heading_deg,
                double tilt_deg, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  BlockImage im;
  im.name = name;
  im.camera_name = "camera";
  // Kappa 0 puts image x along +X (the simulator's convention): a heading
  // along +Y is kappa 90.
  im.camera = Camera::FromAngles(HandCamera(), c, tilt_deg * u(rng), tilt_deg * u(rng), heading_deg,
                                 AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  return im;
}

// Caliterra's flight, simulated: 8 photos climbing to 53 m off to the side,
// then 7 strips flown north and south in turn, 8-10 photos each at steps
// 0.4-1.6 times the mean, headings off the track by up to 18 deg, tracks off
// their line by a tenth of the spacing, and a photo in most turns. Names
// number the photos in flight order; the block lists them shuffled.
Flown HandFlown(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double h = 53, base = 12, spacing = 19;
  Flown f;
  int number = 9354;
  auto name = [&]() { return "IMG_" + std::to_string(number++); };
  std::vector<BlockImage> images;
  const Eigen::Vector2d takeoff(-1.5 * spacing, -1.0 * base);
  for (const double z : {3.0, 8.0, 14.0, 20.0, 26.0, 32.0, 37.0, 41.0}) {
    const Eigen::Vector2d xy = takeoff + 0.1 * base * Eigen::Vector2d(u(rng), u(rng));
    images.push_back(Shot(name(), {xy.x(), xy.y(), z}, 90 + 40 * u(rng), 5, rng));
    f.climb.insert(images.back().name);
  }
  const double length = 8 * base;
  for (int s = 0; s < 7; ++s) {
    const bool north = s % 2 == 0;
    const int n = 8 + static_cast<int>(rng() % 3);
    const double x = s * spacing;
    f.strips.emplace_back();
    double end = 0;
    for (int i = 0; i < n; ++i) {
      const double along = length * (i + 0.3 * u(rng)) / (n - 1);
      end = north ? along : length - along;
      const Eigen::Vector3d c(x + 0.1 * spacing * u(rng), end, h * (1 + 0.03 * u(rng)));
      images.push_back(Shot(name(), c, (north ? 90 : 270) + 18 * u(rng), 3, rng));
      f.strips.back().push_back(images.back().name);
    }
    if (s < 6 && s != 3) {
      // Half-way across to the next strip, a little beyond this one's end.
      const Eigen::Vector3d c(x + 0.5 * spacing, end + (north ? 0.3 : -0.3) * base, h);
      images.push_back(Shot(name(), c, 20 * u(rng), 3, rng));
      f.turns.insert(images.back().name);
    }
  }
  std::shuffle(images.begin(), images.end(), rng);
  f.block.source = "sim/hand-flown";
  f.block.format = "sim";
  f.block.images = images;
  f.block.ground_height = 0;
  f.block.origin = ChooseLocalOrigin(f.block.images);
  return f;
}

std::vector<std::string> Names(const Block& block, const std::vector<int>& ids) {
  std::vector<std::string> out;
  for (const int i : ids) out.push_back(block.images[i].name);
  return out;
}

// Where each image of the plan is: in a group's images, or only its views.
void ExpectEveryImageInAGroup(const Block& block, const GroupingPlan& plan) {
  EXPECT_TRUE(plan.ungrouped.empty()) << ::testing::PrintToString(Names(block, plan.ungrouped));
  std::set<int> seen;
  for (const ImageGroup& g : plan.groups) {
    seen.insert(g.images.begin(), g.images.end());
    seen.insert(g.views.begin(), g.views.end());
  }
  EXPECT_EQ(seen.size(), block.images.size());
}

TEST(HandFlownStrips, StripsAsFlownAndTheClimbAndTurnsAsOutliers) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Flown f = HandFlown(seed);
    const StripDetection d = DetectStrips(f.block);
    std::vector<std::vector<std::string>> strips;
    for (const auto& s : d.strips) strips.push_back(Names(f.block, s));
    EXPECT_EQ(strips, f.strips) << "seed " << seed;
    std::set<std::string> climb, turns, all;
    for (const StripOutlier& o : d.outliers) {
      const std::string& n = f.block.images[o.image].name;
      all.insert(n);
      EXPECT_FALSE(o.reason.empty());
      if (o.kind == OutlierKind::kClimb) climb.insert(n);
      if (o.kind == OutlierKind::kTurn) {
        turns.insert(n);
        EXPECT_NE(o.reason.find("between strips"), std::string::npos) << o.reason;
      }
    }
    EXPECT_EQ(turns, f.turns) << "seed " << seed;
    // Below 0.8 of the strips' height the climb is told by its height; its
    // last photos, nearer the strips' height, are strays before strip 1.
    EXPECT_TRUE(std::includes(f.climb.begin(), f.climb.end(), climb.begin(), climb.end()));
    EXPECT_GE(climb.size(), 6u);
    std::set<std::string> expected = f.climb;
    expected.insert(f.turns.begin(), f.turns.end());
    EXPECT_EQ(all, expected) << "seed " << seed;
  }
}

TEST(HandFlownStrips, FlightOrderComesFromTheNamesNotTheBlockOrder) {
  const Flown f = HandFlown(4);
  const std::vector<int> order = FlightOrder(f.block);
  ASSERT_EQ(order.size(), f.block.images.size());
  for (size_t k = 1; k < order.size(); ++k)
    EXPECT_LT(f.block.images[order[k - 1]].name, f.block.images[order[k]].name);
  // Names that say nothing: the block's order is taken only when it is a
  // path through the centres, else none.
  Flown anon = f;
  for (size_t i = 0; i < anon.block.images.size(); ++i)
    anon.block.images[i].name = "photo" + std::to_string(i);
  EXPECT_TRUE(FlightOrder(anon.block).empty());
}

TEST(HandFlownGroups, NoSmallGroupAndNoImageLeftOutByEitherStrategy) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Flown f = HandFlown(seed);
    const GroupingPlan plan = PlanGroups(f.block, StripOptions(), MatcherOptions{});
    ASSERT_FALSE(plan.single_group);
    for (const ImageGroup& g : plan.groups) {
      EXPECT_GE(g.images.size(), 4u) << "seed " << seed;
      EXPECT_LE(g.images.size(), static_cast<size_t>(StripOptions().max_images));
    }
    ExpectEveryImageInAGroup(f.block, plan);
    // Climb photos see the ground at another GSD: views only.
    for (const StripOutlier& o : plan.outliers) {
      if (o.kind != OutlierKind::kClimb) continue;
      for (const ImageGroup& g : plan.groups)
        EXPECT_EQ(std::count(g.images.begin(), g.images.end(), o.image), 0);
    }
    GroupingOptions tiles;
    tiles.strategy = GroupingStrategy::kFootprint;
    ExpectEveryImageInAGroup(f.block, PlanGroups(f.block, tiles, MatcherOptions{}));
  }
}

TEST(HandFlownGroups, PlanListsTheOutliersAndWhy) {
  const Flown f = HandFlown(1);
  const GroupingPlan plan = PlanGroups(f.block, StripOptions(), MatcherOptions{});
  ASSERT_FALSE(plan.outliers.empty());
  std::ostringstream text;
  PrintPlan(f.block, plan, text);
  const nlohmann::json j = PlanToJson(f.block, plan);
  ASSERT_EQ(j["outliers"].size(), plan.outliers.size());
  for (size_t k = 0; k < plan.outliers.size(); ++k) {
    const StripOutlier& o = plan.outliers[k];
    const std::string& name = f.block.images[o.image].name;
    EXPECT_NE(text.str().find("outlier     " + name + " " + o.reason + "; joins group"),
              std::string::npos)
        << name;
    EXPECT_EQ(j["outliers"][k]["name"], name);
    EXPECT_EQ(j["outliers"][k]["kind"], ToString(o.kind));
    EXPECT_TRUE(j["outliers"][k]["joins"].is_string());
  }
}

// A grid flown as a serpentine with the same spacing along and across
// track, 4 deg between neighbours both ways, and the heading held (a
// multicopter need not turn to fly back).
Block Grid(int strips, int per_strip) {
  const double h = 50, step = h * std::tan(4 * M_PI / 180);
  std::mt19937 rng(5);
  Block block;
  int number = 1;
  for (int s = 0; s < strips; ++s) {
    for (int i = 0; i < per_strip; ++i) {
      const double y = (s % 2 == 0 ? i : per_strip - 1 - i) * step;
      char name[16];
      std::snprintf(name, sizeof(name), "DJI_%04d", number++);
      block.images.push_back(Shot(name, {s * step, y, h}, 90, 0.5, rng));
    }
  }
  block.source = "sim/grid";
  block.format = "sim";
  block.ground_height = 0;
  block.origin = ChooseLocalOrigin(block.images);
  return block;
}

TEST(GridStrips, EqualSpacingBothWaysIsReadAsItsStrips) {
  const Block block = Grid(8, 12);
  const StripDetection d = DetectStrips(block);
  ASSERT_EQ(d.strips.size(), 8u);
  for (size_t s = 0; s < d.strips.size(); ++s) {
    ASSERT_EQ(d.strips[s].size(), 12u);
    for (const int i : d.strips[s]) EXPECT_EQ(i / 12, static_cast<int>(s));
  }
  EXPECT_TRUE(d.outliers.empty());
}

TEST(GridGroups, EveryGroupSpansTwiceTheMaxAngle) {
  const Block block = Grid(8, 12);
  const BlockGeometry geometry = EstimateBlockGeometry(block);
  const std::vector<Footprint> fp = Footprints(block, geometry);
  for (const GroupingStrategy strategy : {GroupingStrategy::kStrip, GroupingStrategy::kFootprint}) {
    for (const double max_angle : {10.0, 15.0}) {
      GroupingOptions o;
      o.strategy = strategy;
      MatcherOptions m;
      m.max_angle_deg = max_angle;
      const GroupingPlan plan = PlanGroups(block, o, m, &geometry);
      int widened = 0;
      for (const ImageGroup& g : plan.groups) {
        const Eigen::Vector2d c = MeanCenter(fp, g.images);
        const Eigen::Vector3d x(c.x(), c.y(), fp[g.images[0]].scene_z);
        EXPECT_GE(SpanDeg(block, g.MatchedIn(), x, m.view_angle_deg), 2 * max_angle)
            << ToString(strategy) << " group of " << g.images.size() << " + " << g.views.size();
        widened += SpanDeg(block, g.images, x, m.view_angle_deg) < 2 * max_angle;
      }
      // The groups' own images do not span it: views from beyond do.
      EXPECT_GT(widened, 0) << ToString(strategy);
    }
  }
}

TEST(GroupingOptions, StrategyNames) {
  EXPECT_EQ(ParseGroupingStrategy("strip"), GroupingStrategy::kStrip);
  EXPECT_EQ(ParseGroupingStrategy("footprint"), GroupingStrategy::kFootprint);
  EXPECT_EQ(ToString(GroupingStrategy::kFootprint), "footprint");
  try {
    ParseGroupingStrategy("strips");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "unknown grouping strategy 'strips': expected strip or footprint");
  }
}

}  // namespace
}  // namespace sapmvs

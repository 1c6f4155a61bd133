#include "match/patch_filter.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <vector>

#include "sapmvs/block/camera.h"

namespace sapmvs {
namespace {

// Nadir cameras 100 m above the ground z = 0 (local frame), 640 x 480 px,
// f = 300 px: a footprint of 1/3 m on the ground.
MatchGroupData NadirGroup(const std::vector<Eigen::Vector3d>& centers) {
  Eigen::Matrix3d r_wc;
  r_wc.row(0) = Eigen::Vector3d(1, 0, 0);
  r_wc.row(1) = Eigen::Vector3d(0, -1, 0);
  r_wc.row(2) = Eigen::Vector3d(0, 0, -1);
  const Intrinsics k = Intrinsics::FromPixels(300, 300, 319.5, 239.5, 640, 480);
  MatchGroupData group;
  for (const Eigen::Vector3d& c : centers) {
    MatchImage im;
    im.camera = Camera(k, r_wc, c);
    group.images.push_back(im);
  }
  return group;
}

struct Points {
  std::vector<DensePoint> points;
  std::vector<AcceptedPatch> patches;

  // A point with a patch of its own.
  int Add(const Eigen::Vector3d& x, int ref, std::vector<int> views, float score) {
    AcceptedPatch p;
    p.center = x;
    p.ref = ref;
    p.views = std::move(views);
    p.score = score;
    p.size = 7;
    patches.push_back(p);
    DensePoint d;
    d.x = x;
    d.patch = static_cast<int>(patches.size()) - 1;
    points.push_back(d);
    return static_cast<int>(points.size()) - 1;
  }
};

// Images 0-2 above the origin match a point 10 m up in the air; images 3-6,
// 60 m east, look past it at the ground 6.7 m west of the origin.
class FreeSpaceTest : public ::testing::Test {
 protected:
  MatchGroupData group = NadirGroup({{-10, 0, 100},
                                     {0, 0, 100},
                                     {10, 0, 100},
                                     {60, 0, 100},
                                     {62, 0, 100},
                                     {64, 0, 100},
                                     {66, 0, 100}});
  MatcherOptions options;
  const Eigen::Vector3d floating{0, 0, 10};
  // Where image 3's ray through `floating` meets the ground.
  const Eigen::Vector3d behind{60 - 60 * 10.0 / 9.0, 0, 0};
};

TEST_F(FreeSpaceTest, APointThatAnotherImageSawTheGroundThroughGoes) {
  Points p;
  const int f = p.Add(floating, 0, {1, 2}, 0.9f);
  p.Add(behind, 3, {4, 5, 6}, 0.95f);
  ASSERT_LT(
      (group.images[3].camera.Project(floating) - group.images[3].camera.Project(behind)).norm(),
      1e-6);
  EXPECT_FALSE(VisibilityFilter(group, options, p.points, p.patches)[f]);
}

TEST_F(FreeSpaceTest, WithoutTheGroundBehindItThePointStays) {
  Points p;
  const int f = p.Add(floating, 0, {1, 2}, 0.9f);
  // The same ground point, seen only by images that do not see it behind
  // the floating point... is not there: a point elsewhere.
  p.Add(behind + Eigen::Vector3d(-20, 0, 0), 3, {4, 5, 6}, 0.95f);
  EXPECT_TRUE(VisibilityFilter(group, options, p.points, p.patches)[f]);
}

TEST_F(FreeSpaceTest, ASurfaceInFrontOfThePointDoesNotRemoveIt) {
  Points p;
  const int f = p.Add(floating, 0, {1, 2}, 0.9f);
  // Halfway between image 3 and the floating point: it hides the point in
  // image 3, which proves nothing against it.
  const Eigen::Vector3d in_front = 0.5 * (floating + group.images[3].camera.center());
  p.Add(in_front, 3, {4, 5, 6}, 0.95f);
  EXPECT_TRUE(VisibilityFilter(group, options, p.points, p.patches)[f]);
}

TEST_F(FreeSpaceTest, AWeakerGroundPointDoesNotOutvoteABetterSupportedOne) {
  Points p;
  // Support (1 + views) x score: 3 x 0.9 for the point, 2 x 0.75 for the
  // ground seen through it.
  const int f = p.Add(floating, 0, {1, 2}, 0.9f);
  p.Add(behind, 3, {4}, 0.75f);
  options.min_image_num = 2;
  EXPECT_TRUE(VisibilityFilter(group, options, p.points, p.patches)[f]);
}

// The free-space test looks for the images that may see a point per box of
// consecutive points: a box whose other points lie far outside image 3, or
// behind every camera, must still have image 3 looked at.
TEST_F(FreeSpaceTest, APointAmongFarOrUnseenPointsStillGoes) {
  for (const Eigen::Vector3d& elsewhere :
       {Eigen::Vector3d(-400, 0, 0), Eigen::Vector3d(0, 0, 300)}) {
    Points p;
    const int f = p.Add(floating, 0, {1, 2}, 0.9f);
    p.Add(behind, 3, {4, 5, 6}, 0.95f);
    for (int i = 0; i < 300; ++i) p.Add(elsewhere + Eigen::Vector3d(0, 0.1 * i, 0), 0, {1}, 0.9f);
    ASSERT_FALSE(group.images[3].camera.InImage(group.images[3].camera.Project(elsewhere)) &&
                 group.images[3].camera.Depth(elsewhere) > 0);
    EXPECT_FALSE(VisibilityFilter(group, options, p.points, p.patches)[f]) << elsewhere.transpose();
  }
}

// A steep plane, its normal 81 degrees from the nadir images' lines of sight
// (Herz-Jesu-P8's ground from its cameras), sampled every 0.3 m across
// (0.9 px): one 2 px cell of an image holds points 1.9 m apart in depth along
// the slope, almost 6 face-on footprints. Counted along the slope, the depth
// tolerance keeps them all; counted face-on (3 footprints, 1 m) it hid the
// deeper points of every cell behind the nearer ones, half the plane.
TEST(VisibilityFilter, ASurfaceSeenObliquelyIsNotHiddenByItself) {
  const MatchGroupData group = NadirGroup({{0, -10, 100}, {0, 0, 100}, {0, 10, 100}});
  const double tilt = 81.0 * std::acos(-1.0) / 180.0;
  const Eigen::Vector3d normal(std::sin(tilt), 0, std::cos(tilt));
  Points p;
  for (int r = 0; r < 21; ++r) {
    for (int c = 0; c < 11; ++c) {
      const double x = -1.5 + 0.3 * c;
      const int i = p.Add(Eigen::Vector3d(x, -3 + 0.3 * r, -x * std::tan(tilt)), 1, {0, 2}, 0.95f);
      p.patches[p.points[i].patch].normal = normal;
    }
  }
  MatcherOptions options;
  const std::vector<bool> keep = VisibilityFilter(group, options, p.points, p.patches);
  long kept = 0;
  for (const bool k : keep) kept += k;
  std::printf("[ filter   ] plane seen at 81 degrees: %ld of %zu points kept\n", kept, keep.size());
  EXPECT_EQ(kept, static_cast<long>(keep.size()));
}

// A flat grid of points under images 0-2, every other one from a weak patch.
Points GridWithWeakPatches(int* weak) {
  Points p;
  *weak = 0;
  for (int r = 0; r < 40; ++r) {
    for (int c = 0; c < 40; ++c) {
      const bool low = (r + c) % 2 == 1;
      p.Add(Eigen::Vector3d(-6 + 0.3 * c, -6 + 0.3 * r, 0), 0, {1, 2}, low ? 0.75f : 0.97f);
      *weak += low;
    }
  }
  return p;
}

TEST(FilterPoints, PointsBelowTheScoreFloorGoAndAreCounted) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  int weak = 0;
  const Points p = GridWithWeakPatches(&weak);
  MatchStats without;
  const std::vector<bool> all = FilterPoints(group, options, p.points, p.patches, &without, 0.0);
  EXPECT_EQ(without.removed_score, 0);
  for (size_t i = 0; i < all.size(); ++i) EXPECT_TRUE(all[i]) << i;

  MatchStats with;
  const std::vector<bool> keep = FilterPoints(group, options, p.points, p.patches, &with, 0.9);
  EXPECT_EQ(with.removed_score, weak);
  EXPECT_EQ(with.removed_visibility + with.removed_neighbourhood + with.removed_clusters, 0);
  for (size_t i = 0; i < keep.size(); ++i) {
    EXPECT_EQ(keep[i], p.patches[p.points[i].patch].score >= 0.9f) << i;
  }
}

TEST(FilterPoints, OneCellPatchesMeetTheirOwnFloor) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  int weak = 0;
  const Points p = GridWithWeakPatches(&weak);
  // The second half of the patches as a pmvs pass's: they face 0.7, the
  // first half 0.9.
  PatchClasses classes(0.9);
  classes.one_cell_first = p.patches.size() / 2;
  classes.one_cell_floor = 0.7;
  MatchStats stats;
  const std::vector<bool> keep = FilterPoints(group, options, p.points, p.patches, &stats, classes);
  long weak_before = 0;
  for (size_t i = 0; i < keep.size(); ++i) {
    const int patch = p.points[i].patch;
    const bool one_cell = classes.OneCell(patch);
    const bool low = p.patches[patch].score < 0.9f;
    weak_before += low && !one_cell;
    EXPECT_EQ(keep[i], one_cell || !low) << i;
  }
  EXPECT_GT(weak_before, 0);
  EXPECT_LT(weak_before, weak) << "weak patches on both sides of one_cell_first";
  EXPECT_EQ(stats.removed_score, weak_before);
}

// Points on the ground whose patches' planes tilt 60 degrees, as a one-cell
// patch's may where its window straddles a roof edge: the patch-support test
// drops them, unless they are a pmvs pass's one-cell patches.
TEST(FilterPoints, OneCellPatchesPlanesAreNotJudgedByTheirNeighbours) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  int weak = 0;
  Points p = GridWithWeakPatches(&weak);
  for (AcceptedPatch& patch : p.patches) patch.score = 0.97f;
  const int first_tilted = static_cast<int>(p.patches.size());
  for (int i = 0; i < 10; ++i) {
    const int k = p.Add(Eigen::Vector3d(-4.35 + 0.9 * i, 0.15, 0), 0, {1, 2}, 0.97f);
    // Tilted towards the grid's diagonal: of the 16 grid points around a
    // cell's centre, 4 lie on its plane.
    const double t = std::sin(M_PI / 3) / std::sqrt(2.0);
    p.patches[p.points[k].patch].normal = Eigen::Vector3d(t, t, std::cos(M_PI / 3));
  }
  MatchStats adaptive_stats;
  const std::vector<bool> adaptive =
      FilterPoints(group, options, p.points, p.patches, &adaptive_stats);
  PatchClasses classes;
  classes.one_cell_first = static_cast<size_t>(first_tilted);
  MatchStats one_cell_stats;
  const std::vector<bool> one_cell =
      FilterPoints(group, options, p.points, p.patches, &one_cell_stats, classes);
  for (size_t i = 0; i < p.points.size(); ++i) {
    const bool tilted = p.points[i].patch >= first_tilted;
    EXPECT_EQ(adaptive[i], !tilted) << i;
    EXPECT_TRUE(one_cell[i]) << i;
  }
  EXPECT_EQ(adaptive_stats.removed_neighbourhood, 10);
  EXPECT_EQ(one_cell_stats.removed_neighbourhood, 0);
}

// An early pass's filter (MatcherOptions::visibility_only_filters): the
// score floor and the visibility test decide alone, so the tilted patches
// that the patch-support test drops above stay, and the weak ones go.
TEST(FilterPoints, ScoreAndVisibilityAloneLeaveTheNeighbourhoodTests) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  int weak = 0;
  Points p = GridWithWeakPatches(&weak);
  const int first_tilted = static_cast<int>(p.patches.size());
  for (int i = 0; i < 10; ++i) {
    const int k = p.Add(Eigen::Vector3d(-4.35 + 0.9 * i, 0.15, 0), 0, {1, 2}, 0.97f);
    const double t = std::sin(M_PI / 3) / std::sqrt(2.0);
    p.patches[p.points[k].patch].normal = Eigen::Vector3d(t, t, std::cos(M_PI / 3));
  }
  const PatchClasses floor(0.9);
  MatchStats all_stats, light_stats;
  const std::vector<bool> all =
      FilterPoints(group, options, p.points, p.patches, &all_stats, floor, FilterTests::kAll);
  const std::vector<bool> light = FilterPoints(group, options, p.points, p.patches, &light_stats,
                                               floor, FilterTests::kScoreAndVisibility);
  std::vector<bool> eligible(p.points.size());
  for (size_t i = 0; i < p.points.size(); ++i)
    eligible[i] = p.patches[p.points[i].patch].score >= 0.9f;
  const std::vector<bool> visible = VisibilityFilter(group, options, p.points, p.patches, eligible);
  long tilted_kept = 0;
  for (size_t i = 0; i < p.points.size(); ++i) {
    EXPECT_EQ(light[i], visible[i]) << i;
    if (all[i]) {
      EXPECT_TRUE(light[i]) << i;
    }
    tilted_kept += light[i] && p.points[i].patch >= first_tilted;
  }
  EXPECT_EQ(tilted_kept, 10);
  EXPECT_EQ(light_stats.removed_score, weak);
  EXPECT_EQ(all_stats.removed_score, weak);
  EXPECT_GT(all_stats.removed_neighbourhood, 0);
  EXPECT_EQ(light_stats.removed_neighbourhood, 0);
  EXPECT_EQ(light_stats.removed_clusters, 0);
}

// A pixel of disparity in a view 60 m off a nadir reference at 100 m (31
// degrees between the rays) moves a ground point 1.94 footprints in depth,
// in one 10 m off (5.7 degrees) 10.0 footprints.
TEST(DisparityDepth, IsTheViewsFootprintOverTheSineOfTheirAngle) {
  const MatchGroupData group = NadirGroup({{0, 0, 100}, {60, 0, 100}, {10, 0, 100}, {0, 0, 50}});
  Points p;
  const int k = p.Add(Eigen::Vector3d(0, 0, 0), 0, {1, 2}, 0.9f);
  const AcceptedPatch& patch = p.patches[p.points[k].patch];
  EXPECT_NEAR(DisparityDepth(group, patch), std::sqrt(60.0 * 60 + 100 * 100) / 60, 1e-9);
  AcceptedPatch narrow = patch;
  narrow.views = {2};
  EXPECT_NEAR(DisparityDepth(group, narrow), std::sqrt(10.0 * 10 + 100 * 100) / 10, 1e-9);
  // A view on the reference's ray resolves nothing; a view at half the
  // reference's distance has half its footprint.
  AcceptedPatch none = patch;
  none.views = {3};
  EXPECT_TRUE(std::isinf(DisparityDepth(group, none)));
  none.views.clear();
  EXPECT_TRUE(std::isinf(DisparityDepth(group, none)));
  AcceptedPatch nearer = patch;
  nearer.ref = 3;
  nearer.views = {1};
  const double sine = 60 / std::sqrt(60.0 * 60 + 100 * 100);
  EXPECT_NEAR(DisparityDepth(group, nearer), 2.0 / sine, 1e-9);
}

// One-cell patches 1.5 footprints (0.5 m) above a flat grid, beyond its
// 0.5-footprint plane tolerance: the neighbourhood test keeps those whose
// views resolve their depth to within pmvs_pass_plane_tolerance (a view 60 m
// off, 1.94 footprints), not those seen from 10 m off (10 footprints), nor
// adaptive patches there, nor any at pmvs_pass_plane_tolerance 0.
TEST(FilterPoints, OneCellPatchesResolvedByTheirViewsMeetTheirOwnPlaneTolerance) {
  const MatchGroupData group =
      NadirGroup({{0, 0, 100}, {60, 0, 100}, {-60, 0, 100}, {10, 0, 100}, {-10, 0, 100}});
  int weak = 0;
  Points p = GridWithWeakPatches(&weak);
  for (AcceptedPatch& patch : p.patches) patch.score = 0.97f;
  const int first_raised = static_cast<int>(p.patches.size());
  std::vector<int> wide, narrow;
  for (int i = 0; i < 6; ++i) {
    const Eigen::Vector3d x(-4.35 + 1.8 * i, -2.85, 0.5);
    wide.push_back(p.Add(x, 0, {1, 2}, 0.97f));
    narrow.push_back(p.Add(x + Eigen::Vector3d(0, 5.4, 0), 0, {3, 4}, 0.97f));
  }
  MatcherOptions options;
  ASSERT_EQ(options.pmvs_pass_plane_tolerance, 2.0);
  PatchClasses classes;
  classes.one_cell_first = static_cast<size_t>(first_raised);
  auto run = [&](const PatchClasses& c, MatchStats* stats) {
    return FilterPoints(group, options, p.points, p.patches, stats, c);
  };
  MatchStats one_cell_stats, adaptive_stats, off_stats;
  const std::vector<bool> one_cell = run(classes, &one_cell_stats);
  const std::vector<bool> adaptive = run(PatchClasses(), &adaptive_stats);
  EXPECT_DOUBLE_EQ(one_cell_stats.plane_tolerance, 0.5);
  for (const int k : wide) {
    EXPECT_TRUE(one_cell[k]) << k;
    EXPECT_FALSE(adaptive[k]) << k;
  }
  for (const int k : narrow) {
    EXPECT_FALSE(one_cell[k]) << k;
    EXPECT_FALSE(adaptive[k]) << k;
  }
  EXPECT_EQ(one_cell_stats.removed_neighbourhood, 6);
  EXPECT_EQ(adaptive_stats.removed_neighbourhood, 12);
  options.pmvs_pass_plane_tolerance = 0;
  const std::vector<bool> off = run(classes, &off_stats);
  for (const int k : wide) EXPECT_FALSE(off[k]) << k;
  EXPECT_EQ(off_stats.removed_neighbourhood, 12);
  // The grid itself stays whole throughout.
  for (int k = 0; k < first_raised; ++k) {
    EXPECT_TRUE(one_cell[k] && adaptive[k] && off[k]) << k;
  }
}

TEST(FilterPoints, PointsBelowTheScoreFloorHideNothing) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  int weak = 0;
  Points p = GridWithWeakPatches(&weak);
  // A weak but many-viewed point 5 m above the grid's centre would hide the
  // good points under it in every image if it took part.
  for (int i = 0; i < 6; ++i) p.Add(Eigen::Vector3d(0.01 * i, 0, 5), 0, {1, 2}, 0.8f);
  MatchStats with;
  const std::vector<bool> keep = FilterPoints(group, options, p.points, p.patches, &with, 0.9);
  EXPECT_EQ(with.removed_score, weak + 6);
  long good = 0;
  for (size_t i = 0; i < keep.size(); ++i) good += keep[i];
  EXPECT_EQ(good, 40 * 40 - weak);
}

// A plane with depth noise of half a footprint (1/6 m) between patches, and
// one patch 3 footprints above it.
Points NoisyPlane(int* outlier) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.5 / 3.0);
  Points p;
  for (int r = 0; r < 41; ++r) {
    for (int c = 0; c < 41; ++c) {
      p.Add(Eigen::Vector3d(-6 + 0.3 * c, -6 + 0.3 * r, noise(rng)), 0, {1, 2}, 0.95f);
    }
  }
  *outlier = p.Add(Eigen::Vector3d(0.05, 0.05, 1.0), 0, {1, 2}, 0.95f);
  return p;
}

TEST(FilterPoints, ThePlaneToleranceFollowsTheNoiseBetweenPatches) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  int outlier = -1;
  const Points p = NoisyPlane(&outlier);
  auto kept_share = [&](const std::vector<bool>& keep) {
    long n = 0;
    for (size_t i = 0; i < keep.size(); ++i) n += keep[i] && static_cast<int>(i) != outlier;
    return static_cast<double>(n) / (keep.size() - 1);
  };
  MatcherOptions fixed;
  fixed.plane_sigmas = 0;
  MatchStats fs;
  const std::vector<bool> a = FilterPoints(group, fixed, p.points, p.patches, &fs);
  EXPECT_EQ(fs.plane_tolerance, fixed.plane_tolerance);
  MatcherOptions adaptive;
  MatchStats as;
  const std::vector<bool> b = FilterPoints(group, adaptive, p.points, p.patches, &as);
  // The distance between two noisy patches is half-normal with sigma
  // sqrt(2) / 6 m = 0.71 footprints, 1.5 of them 1.06; the nearest
  // neighbours in 3D favour the closer depths, which takes a little off.
  EXPECT_GT(as.plane_tolerance, 0.8);
  EXPECT_LT(as.plane_tolerance, 1.5 * 0.5 * std::sqrt(2.0) + 0.1);
  std::printf("[ filter   ] noisy plane: kept %.3f with 0.5 footprints, %.3f with %.2f\n",
              kept_share(a), kept_share(b), as.plane_tolerance);
  EXPECT_LT(kept_share(a), 0.8);
  EXPECT_GT(kept_share(b), 0.9);
  EXPECT_FALSE(a[outlier]);
  EXPECT_FALSE(b[outlier]);
}

// Flat blocks of points over 5 m apart (15 footprints, beyond the
// neighbour radius), each a cluster of its own: one on either side of
// min_cluster_size (30), and a large one. The points are shuffled, so that a
// cluster's points lie in both halves of the point order that the threads of
// the cluster search share.
TEST(FilterPoints, ClustersBelowTheMinimumSizeGoWhicheverThreadSawThem) {
  const MatchGroupData group = NadirGroup({{-10, 0, 100}, {0, 0, 100}, {10, 0, 100}});
  MatcherOptions options;
  ASSERT_EQ(options.min_cluster_size, 30);
  const int blocks[][2] = {{6, 4}, {5, 6}, {4, 7}, {7, 5}, {20, 20}};
  std::vector<std::pair<Eigen::Vector3d, int>> all;  // point, its block's size
  for (size_t b = 0; b < std::size(blocks); ++b) {
    const int cols = blocks[b][0], rows = blocks[b][1];
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        all.push_back({Eigen::Vector3d(-30 + 12.0 * b + 0.3 * c, 0.3 * r, 0), cols * rows});
      }
    }
  }
  std::shuffle(all.begin(), all.end(), std::mt19937(5));
  Points p;
  for (const auto& [x, size] : all) p.Add(x, 0, {1, 2}, 0.95f);
  MatchStats stats;
  const std::vector<bool> keep = FilterPoints(group, options, p.points, p.patches, &stats, 0.0);
  long small = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    const int size = all[i].second;
    EXPECT_EQ(keep[i], size >= 30) << "point " << i << " of a block of " << size;
    small += size < 30;
  }
  EXPECT_EQ(stats.removed_clusters, small);
  EXPECT_EQ(small, 24 + 28);
}

TEST(SeedDepthFences, TukeyFencesPaddedByTenGsdAndNoneBelowTenSeeds) {
  std::vector<std::vector<double>> depths(2);
  for (int i = 0; i < 9; ++i) depths[0].push_back(100.0 + i);
  // 20 depths 100..119, shuffled: the fence must not depend on their order.
  for (int i = 0; i < 20; ++i) depths[1].push_back(100.0 + (i * 7) % 20);
  const double gsd = 0.05;
  const auto fences = SeedDepthFences(depths, {}, gsd);
  ASSERT_EQ(fences.size(), 2u);
  EXPECT_EQ(fences[0], std::make_pair(0.0, 0.0)) << "9 seeds are too few for a fence";
  // Quartiles of 100..119 at indices 5 and 15: 105 and 115.
  const double pad = 3.0 * (115.0 - 105.0) + 10.0 * gsd;
  EXPECT_DOUBLE_EQ(fences[1].first, 105.0 - pad);
  EXPECT_DOUBLE_EQ(fences[1].second, 115.0 + pad);
}

// Most seeds on the ground at depth ~500 and a few on a tower's roof at 432
// (city's 66 m tower): Tukey's near fence would cut the roof; the near fence
// is where the seed search stopped looking, so the roof stays. The far fence
// stays Tukey's, which drops the false seeds' clusters behind the ground.
TEST(SeedDepthFences, NearFenceIsTheSeedSearchsNearEndFarFenceIsTukeys) {
  std::vector<std::vector<double>> depths(3);
  for (int i = 0; i < 97; ++i) depths[0].push_back(495.0 + (i * 13) % 11);
  for (double d : {432.0, 433.0, 990.0}) depths[0].push_back(d);
  depths[1] = depths[0];
  depths[2] = depths[0];
  const double gsd = 0.95;
  const auto tukey = SeedDepthFences(depths, {}, gsd);
  EXPECT_GT(tukey[0].first, 432.0) << "Tukey's near fence alone would cut the roof";
  const auto fences = SeedDepthFences(depths, {250.0, 0.0, 480.0}, gsd);
  ASSERT_EQ(fences.size(), 3u);
  EXPECT_DOUBLE_EQ(fences[0].first, 250.0) << "the seed search looked as near as 250";
  EXPECT_DOUBLE_EQ(fences[1].first, tukey[1].first) << "no search bound given: Tukey's";
  EXPECT_DOUBLE_EQ(fences[2].first, tukey[2].first) << "a search bound behind Tukey's fence";
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(fences[i].second, tukey[i].second);
    EXPECT_LT(fences[i].second, 990.0) << "the false seed's depth stays outside";
  }
}

// n points, each with a patch of its own scoring score(i), and options with
// a fence 2 robust SDs wide above a 0.7 threshold.
struct Scored {
  MatcherOptions options;
  std::vector<AcceptedPatch> patches;
  std::vector<DensePoint> points;
};
Scored ScoredPoints(int n, const std::function<float(int)>& score) {
  Scored s;
  s.options.threshold = 0.7;
  s.options.score_fence = 2.0;
  s.patches.resize(n);
  s.points.resize(n);
  for (int i = 0; i < n; ++i) {
    s.patches[i].score = score(i);
    s.points[i].patch = i;
  }
  return s;
}

TEST(ScoreFloor, ThresholdUnlessTheFenceLiesAboveIt) {
  auto [options, patches, points] =
      ScoredPoints(20, [](int i) { return 0.95f + 0.001f * static_cast<float>(i % 5); });
  const double tight = ScoreFloor(options, points, patches);
  EXPECT_GT(tight, 0.9) << "scores within 0.004 of each other: the fence lies well above 0.7";
  for (int i = 0; i < 10; ++i) patches[i].score = 0.3f + 0.06f * static_cast<float>(i);
  EXPECT_DOUBLE_EQ(ScoreFloor(options, points, patches), options.threshold)
      << "widely spread scores: the fence falls below the threshold";
  options.score_fence = 0;
  points.resize(5);
  EXPECT_DOUBLE_EQ(ScoreFloor(options, points, patches), options.threshold);
}

TEST(ScoreFloor, OfThePatchesFromFirstPatchOn) {
  // The first 20 tight near 0.98, the last 20 tight near 0.90.
  const auto [options, patches, points] = ScoredPoints(
      40, [](int i) { return (i < 20 ? 0.98f : 0.90f) + 0.001f * static_cast<float>(i % 5); });
  const double all = ScoreFloor(options, points, patches);
  const double later = ScoreFloor(options, points, patches, 20);
  EXPECT_GT(later, 0.89);
  EXPECT_LT(later, 0.90) << "the later patches' own fence";
  EXPECT_LT(all, later) << "both groups together spread the scores";
  EXPECT_DOUBLE_EQ(ScoreFloor(options, points, patches, 35), options.threshold)
      << "fewer than 10 points: the threshold";
}

}  // namespace
}  // namespace sapmvs

#include "sapmvs/run/cloud_merge.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <random>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// A grid of points on z = height over [x0, x1) x [y0, y1) at `spacing`,
// shifted by (dx, dy), with `score`.
PointCloud Grid(double x0, double x1, double y0, double y1, double spacing, double dx, double dy,
                double height, float score) {
  PointCloud c;
  c.has_scores = true;
  for (double y = y0; y < y1; y += spacing) {
    for (double x = x0; x < x1; x += spacing) {
      CloudPoint p;
      p.position = {500000.0 + x + dx, 5400000.0 + y + dy, height};
      p.score = score;
      c.points.push_back(p);
    }
  }
  return c;
}

// `n` points with random scores, uniform in a box of side `side` (a tenth of
// it high) at (x0, x0), dealt alternately to *a and *b.
void RandomPair(int n, double side, double x0, PointCloud* a, PointCloud* b) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, side);
  for (int i = 0; i < n; ++i) {
    CloudPoint p;
    p.position = {x0 + u(rng), x0 + u(rng), 0.1 * u(rng)};
    p.score = static_cast<float>(u(rng));
    (i % 2 ? a : b)->points.push_back(p);
  }
}

long CrossGroupPairsWithin(const PointCloud& merged, const std::vector<int>& group_of, double r) {
  long pairs = 0;
  for (size_t i = 0; i < merged.points.size(); ++i) {
    for (size_t j = i + 1; j < merged.points.size(); ++j) {
      if (group_of[i] != group_of[j] &&
          (merged.points[i].position - merged.points[j].position).norm() <= r) {
        ++pairs;
      }
    }
  }
  return pairs;
}

TEST(CloudMerge, OverlapKeepsEachSurfacePointOnceWithoutHoles) {
  // Two groups matched the same plane over overlapping strips, offset by a
  // third of the spacing (different reference images sample it differently).
  const double s = 0.5;
  const PointCloud a = Grid(0, 20, 0, 10, s, 0, 0, 100, 0.9f);
  const PointCloud b = Grid(12, 32, 0, 10, s, s / 3, s / 3, 100, 0.8f);
  std::vector<GroupCloud> groups = {{&a, {500010.0, 5400005.0}}, {&b, {500022.0, 5400005.0}}};
  MergeOptions o;
  o.radius = s;
  MergeStats st;
  const PointCloud m = MergeGroupClouds(groups, o, &st);
  EXPECT_EQ(st.input, static_cast<long>(a.points.size() + b.points.size()));
  EXPECT_EQ(st.kept + st.duplicates, st.input);
  EXPECT_EQ(st.kept, static_cast<long>(m.points.size()));
  EXPECT_GT(st.duplicates, 0);
  // The output lists group a's kept points first, then b's.
  std::vector<int> group_of;
  for (long k = 0; k < st.kept_by_group[0]; ++k) group_of.push_back(0);
  for (long k = 0; k < st.kept_by_group[1]; ++k) group_of.push_back(1);
  // Allowing the 0.25 GSD of the acceptance, with radius = 1 point spacing.
  EXPECT_EQ(CrossGroupPairsWithin(m, group_of, 0.25 * s), 0);
  EXPECT_EQ(CrossGroupPairsWithin(m, group_of, s), 0);
  // No hole: every point of either input has a merged point within the radius.
  for (const PointCloud* c : {&a, &b}) {
    for (const CloudPoint& p : c->points) {
      bool near = false;
      for (const CloudPoint& q : m.points) {
        if ((q.position - p.position).norm() <= s) {
          near = true;
          break;
        }
      }
      ASSERT_TRUE(near) << p.position.transpose();
    }
  }
  // The core decides the overlap: left of x = 16 (midway between the
  // centres) is a's, right of it b's.
  for (size_t i = 0; i < m.points.size(); ++i) {
    const double x = m.points[i].position.x() - 500000.0;
    if (x < 15.5) {
      EXPECT_EQ(group_of[i], 0) << x;
    }
    if (x > 16.5) {
      EXPECT_EQ(group_of[i], 1) << x;
    }
  }
}

TEST(CloudMerge, AHoleInTheOwnerIsFilledByTheOtherGroup) {
  const double s = 0.5;
  PointCloud a = Grid(0, 20, 0, 10, s, 0, 0, 100, 0.9f);
  // Group a matched nothing in [14, 18) x [2, 6): b's points must fill it.
  std::vector<CloudPoint> kept;
  for (const CloudPoint& p : a.points) {
    const double x = p.position.x() - 500000.0, y = p.position.y() - 5400000.0;
    if (!(x >= 14 && x < 18 && y >= 2 && y < 6)) kept.push_back(p);
  }
  a.points = kept;
  const PointCloud b = Grid(10, 30, 0, 10, s, 0.1, 0.1, 100, 0.5f);
  std::vector<GroupCloud> groups = {{&a, {500000.0, 5400005.0}}, {&b, {500040.0, 5400005.0}}};
  MergeOptions o;
  o.radius = s;
  auto in_hole = [](const PointCloud& m, double inset) {
    long n = 0;
    for (const CloudPoint& p : m.points) {
      const double x = p.position.x() - 500000.0, y = p.position.y() - 5400000.0;
      if (x >= 14 + inset && x < 18 - inset && y >= 2 + inset && y < 6 - inset) ++n;
    }
    return n;
  };
  // b's points more than outside_core_radii radii from a's fill the hole:
  // at x and y 15.1, 15.6 and 16.1 by default (3 radii: 1.5 from a's rim at
  // 13.5 and 18, 0.5 and 6).
  EXPECT_EQ(in_hole(MergeGroupClouds(groups, o), 0), 3 * 3);
  o.outside_core_radii = 1;
  EXPECT_GE(in_hole(MergeGroupClouds(groups, o), 0.6), 5 * 5);
}

TEST(CloudMerge, AnotherGroupsLayerJustOffTheOwnersSurfaceIsNotStacked) {
  // With real orientations two groups place the same ground a little apart:
  // b's points lie between a's, 0.8 spacings higher, 1.07 spacings from
  // the nearest of a's. Over a's core they are another layer of a's surface.
  const double s = 0.5;
  const PointCloud a = Grid(0, 20, 0, 10, s, 0, 0, 100, 0.5f);
  const PointCloud b = Grid(0, 20, 0, 10, s, s / 2, s / 2, 100 + 0.8 * s, 0.9f);
  std::vector<GroupCloud> groups = {{&a, {500000.0, 5400005.0}}, {&b, {500040.0, 5400005.0}}};
  MergeOptions o;
  o.radius = s;
  MergeStats st;
  MergeGroupClouds(groups, o, &st);
  EXPECT_EQ(st.kept_by_group[0], static_cast<long>(a.points.size()));
  EXPECT_EQ(st.kept_by_group[1], 0);
  // At one radius, as the merge judged every point, b's layer stayed.
  o.outside_core_radii = 1;
  MergeGroupClouds(groups, o, &st);
  EXPECT_EQ(st.kept_by_group[1], static_cast<long>(b.points.size()));
}

TEST(CloudMerge, AnotherGroupsSurfaceAboveTheOwnersAlongItsNormalIsNotStacked) {
  // b placed a's ground (a crown, a hedge) 2.5 radii higher, a little
  // aside: farther than outside_core_radii from every point of a, but
  // within that of the line along its normal. Where a has a hole, b fills it.
  const double s = 0.5;
  PointCloud a = Grid(0, 10, 0, 10, s, 0, 0, 100, 0.5f);
  a.points.erase(std::remove_if(a.points.begin(), a.points.end(),
                                [](const CloudPoint& p) { return p.position.x() >= 500006.0; }),
                 a.points.end());
  PointCloud b = Grid(0, 10, 0, 10, s, s / 2, s / 2, 100 + 2.5 * s, 0.9f);
  for (PointCloud* c : {&a, &b}) {
    c->has_normals = true;
    for (CloudPoint& p : c->points) p.normal = Eigen::Vector3f::UnitZ();
  }
  std::vector<GroupCloud> groups = {{&a, {500005.0, 5400005.0}}, {&b, {500040.0, 5400005.0}}};
  MergeOptions o;
  o.radius = s;
  o.outside_core_radii = 1.5;
  auto kept_b = [&](double x0, double x1) {
    long n = 0;
    for (const MergedRef& r : MergeGroupRefs(groups, o)) {
      const double x = groups[r.group].cloud->points[r.index].position.x();
      n += r.group == 1 && x >= x0 && x < x1;
    }
    return n;
  };
  // b's columns over a's ground (x 0.25 to 5.25) and over the hole, beyond
  // 1.5 radii of a's last column (6.75 to 9.75), 20 points each.
  const long b_over_a = 11 * 20, b_in_hole = 7 * 20;
  EXPECT_EQ(kept_b(500000.0, 500005.5), 0);
  EXPECT_EQ(kept_b(500006.5, 500010.5), b_in_hole);
  // Judged by the sphere alone, the layer stays; so it does without normals.
  o.surface_depth_radii = 0;
  EXPECT_EQ(kept_b(500000.0, 500005.5), b_over_a);
  o.surface_depth_radii = 10;
  for (CloudPoint& p : b.points) p.normal = Eigen::Vector3f::Zero();
  EXPECT_EQ(kept_b(500000.0, 500005.5), b_over_a);
}

TEST(CloudMerge, BothGroupsAreKeptWithinTheBlendBandOfTheirBorder) {
  // Both groups matched all of [0, 20) x [0, 10), a little apart as with
  // real orientations; their cores meet at x = 10.
  const double s = 0.5;
  const PointCloud a = Grid(0, 20, 0, 10, s, 0, 0, 100, 0.5f);
  const PointCloud b = Grid(0, 20, 0, 10, s, s / 2, s / 2, 100 + 0.8 * s, 0.9f);
  std::vector<GroupCloud> groups = {{&a, {500005.0, 5400005.0}}, {&b, {500015.0, 5400005.0}}};
  MergeOptions o;
  o.radius = s;
  o.blend_radii = 3;
  const double band = o.blend_radii * o.radius;
  const std::vector<MergedRef> kept = MergeGroupRefs(groups, o);
  long in_band = 0, kept_in_band = 0;
  for (const auto* c : {&a, &b}) {
    for (const CloudPoint& p : c->points) in_band += std::abs(p.position.x() - 500010.0) < band;
  }
  for (const MergedRef& r : kept) {
    const double x = groups[r.group].cloud->points[r.index].position.x();
    kept_in_band += std::abs(x - 500010.0) < band;
    // Beyond the band only the owner's points stay.
    if (std::abs(x - 500010.0) >= band) {
      EXPECT_TRUE(r.core) << r.group << " at " << x;
    }
  }
  EXPECT_EQ(kept_in_band, in_band);
  EXPECT_GT(in_band, 0);
  // Without the band, the owner's points alone, up to the border.
  o.blend_radii = 0;
  for (const MergedRef& r : MergeGroupRefs(groups, o)) EXPECT_TRUE(r.core);
}

// Two groups matched the ground (z = 100) on both sides of their border at
// x = 10, with normals up; `cluster` is added to a's points.
std::vector<MergedRef> MergeWithCluster(const PointCloud& cluster, const MergeOptions& o,
                                        PointCloud* a, PointCloud* b, MergeStats* st) {
  const double s = 0.1;
  *a = Grid(5, 15, 0, 4, s, 0, 0, 100, 0.5f);
  *b = Grid(5, 15, 0, 4, s, s / 2, s / 2, 100.02, 0.9f);
  a->points.insert(a->points.end(), cluster.points.begin(), cluster.points.end());
  for (PointCloud* c : {a, b}) {
    c->has_normals = true;
    for (CloudPoint& p : c->points) {
      if (p.normal.isZero()) p.normal = Eigen::Vector3f::UnitZ();
    }
  }
  std::vector<GroupCloud> groups = {{a, {500005.0, 5400002.0}}, {b, {500015.0, 5400002.0}}};
  return MergeGroupRefs(groups, o, st);
}

// How many of `refs` are group 0's points from `first` on (the cluster).
long KeptFrom(const std::vector<MergedRef>& refs, size_t first) {
  return std::count_if(refs.begin(), refs.end(),
                       [&](const MergedRef& r) { return r.group == 0 && r.index >= first; });
}

TEST(CloudMerge, AClusterUnderTheGroundByABorderIsVotedOut) {
  // a matched a patch 1.5 m under the ground, within a few radii of the
  // border: the blend band keeps it, and the other group's ground lies
  // beyond surface_depth_radii of it, so the duplicate test cannot see it.
  MergeOptions o;
  o.radius = 0.1;
  o.blend_radii = 2;
  const size_t first = Grid(5, 15, 0, 4, 0.1, 0, 0, 100, 0.5f).points.size();
  auto cluster_at = [](double x0, double height, const Eigen::Vector3f& normal) {
    PointCloud c = Grid(x0, x0 + 0.3, 1.8, 2.1, 0.1, 0, 0, height, 0.95f);
    for (CloudPoint& p : c.points) p.normal = normal;
    return c;
  };
  const Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
  const PointCloud by_border = cluster_at(9.9, 98.5, up);
  PointCloud a, b;
  MergeStats st;
  EXPECT_EQ(KeptFrom(MergeWithCluster(by_border, o, &a, &b, &st), first), 0);
  EXPECT_EQ(st.band_outliers, static_cast<long>(by_border.points.size()));
  // Without the vote it stays; far from the border it is the group's own
  // affair (its filter's); a tilted patch amid the ground goes too.
  o.vote_zone_radii = 0;
  EXPECT_EQ(KeptFrom(MergeWithCluster(by_border, o, &a, &b, &st), first),
            static_cast<long>(by_border.points.size()));
  EXPECT_EQ(st.band_outliers, 0);
  o.vote_zone_radii = 40;
  const PointCloud far = cluster_at(5.2, 98.5, up);
  EXPECT_EQ(KeptFrom(MergeWithCluster(far, o, &a, &b, &st), first),
            static_cast<long>(far.points.size()));
  const PointCloud tilted = cluster_at(9.9, 98.5, Eigen::Vector3f(1, 0, 0.3f).normalized());
  EXPECT_EQ(KeptFrom(MergeWithCluster(tilted, o, &a, &b, &st), first), 0);
}

TEST(CloudMerge, TheVoteLeavesCrownsAndWallsByABorder) {
  MergeOptions o;
  o.radius = 0.1;
  o.blend_radii = 2;
  const size_t first = Grid(5, 15, 0, 4, 0.1, 0, 0, 100, 0.5f).points.size();
  // A crown 8 m over the ground (beyond the vote's reach of 6 m): another
  // surface, not a wrong match of this one.
  PointCloud crown = Grid(9.8, 10.2, 1.8, 2.2, 0.05, 0, 0, 108, 0.95f);
  PointCloud a, b;
  MergeStats st;
  EXPECT_EQ(KeptFrom(MergeWithCluster(crown, o, &a, &b, &st), first),
            static_cast<long>(crown.points.size()));
  // A wall 3 m high along y = 2, facing south: its points' columns hold the
  // wall above and below them, which does not vote; the ground at its foot
  // stays too.
  PointCloud wall;
  for (double z = 100.05; z < 103; z += 0.05) {
    for (double x = 9.8; x < 10.2; x += 0.05) {
      CloudPoint p;
      p.position = {500000.0 + x, 5400002.0, z};
      p.normal = -Eigen::Vector3f::UnitY();
      p.score = 0.9f;
      wall.points.push_back(p);
    }
  }
  const std::vector<MergedRef> kept = MergeWithCluster(wall, o, &a, &b, &st);
  EXPECT_EQ(KeptFrom(kept, first), static_cast<long>(wall.points.size()));
  EXPECT_EQ(st.band_outliers, 0);
}

TEST(CloudMerge, SurfacesAtOtherHeightsAreNotDuplicates) {
  // A roof 5 m above the ground seen by another group is another surface.
  const PointCloud a = Grid(0, 5, 0, 5, 0.5, 0, 0, 100, 0.9f);
  const PointCloud b = Grid(0, 5, 0, 5, 0.5, 0, 0, 105, 0.9f);
  std::vector<GroupCloud> groups = {{&a, {500000.0, 5400000.0}}, {&b, {500100.0, 5400000.0}}};
  MergeOptions o;
  o.radius = 0.5;
  MergeStats st;
  const PointCloud m = MergeGroupClouds(groups, o, &st);
  EXPECT_EQ(st.duplicates, 0);
  EXPECT_EQ(m.points.size(), a.points.size() + b.points.size());
}

TEST(CloudMerge, PointsOfOneGroupAreNeverDroppedForEachOther) {
  PointCloud a = Grid(0, 3, 0, 3, 0.1, 0, 0, 100, 0.9f);  // denser than the radius
  std::vector<GroupCloud> groups = {{&a, {500000.0, 5400000.0}}};
  MergeOptions o;
  o.radius = 0.5;
  EXPECT_EQ(MergeGroupClouds(groups, o).points.size(), a.points.size());
}

TEST(CloudMerge, SameInputsGiveTheSameOutput) {
  PointCloud a, b;
  RandomPair(997, 10, 0, &a, &b);
  std::vector<GroupCloud> groups = {{&a, {2.0, 5.0}}, {&b, {8.0, 5.0}}};
  MergeOptions o;
  o.radius = 0.3;
  const PointCloud m1 = MergeGroupClouds(groups, o);
  const PointCloud m2 = MergeGroupClouds(groups, o);
  ASSERT_EQ(m1.points.size(), m2.points.size());
  for (size_t i = 0; i < m1.points.size(); ++i) {
    EXPECT_EQ(m1.points[i].position, m2.points[i].position);
  }
}

// The merge keeps, in order of core first and then score, each point with
// no kept point of another group within the radius (outside_core_radii
// radii for a point outside its core, of the line along its normal where it
// has one, and surface_depth_radii along it). Checked pair by pair
// against every kept point on three groups: two that overlap in a band and
// one apart, whose points the merge keeps without looking them up.
TEST(CloudMerge, KeepsWhatTheGreedyPassOverAllPairsKeeps) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const double boxes[3][2] = {{0, 10}, {8, 18}, {30, 40}};  // x ranges; y in [0, 10]
  std::vector<PointCloud> clouds(3);
  for (int g = 0; g < 3; ++g) {
    for (int i = 0; i < 500; ++i) {
      CloudPoint p;
      const double x = boxes[g][0] + (boxes[g][1] - boxes[g][0]) * u(rng);
      p.position = {500000.0 + x, 5400000.0 + 10 * u(rng), 0.2 * u(rng)};
      p.score = static_cast<float>(u(rng));
      // Every other point with a steep normal (a wall), the others without.
      if (i % 2 == 0) p.normal = Eigen::Vector3f(1.0f, 0.2f, 0.4f).normalized();
      clouds[g].points.push_back(p);
    }
  }
  std::vector<GroupCloud> groups;
  for (int g = 0; g < 3; ++g) {
    groups.push_back({&clouds[g], {500000.0 + 0.5 * (boxes[g][0] + boxes[g][1]), 5400005.0}});
  }
  MergeOptions o;
  o.radius = 0.15;
  o.outside_core_radii = 2.5;
  o.surface_depth_radii = 4;
  MergeStats stats;
  const std::vector<MergedRef> merged = MergeGroupRefs(groups, o, &stats);

  struct Item {
    int group;
    size_t index;
    bool core;
    float score;
  };
  std::vector<Eigen::Vector2d> centers;
  for (const GroupCloud& g : groups) centers.push_back(g.center);
  std::vector<Item> items;
  for (int g = 0; g < 3; ++g) {
    for (size_t i = 0; i < clouds[g].points.size(); ++i) {
      const Eigen::Vector3d& p = clouds[g].points[i].position;
      items.push_back({g, i, CoreOwner(centers, p.x(), p.y()) == g, clouds[g].points[i].score});
    }
  }
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    return a.core != b.core ? a.core : a.score > b.score;
  });
  std::vector<Item> kept;
  for (const Item& item : items) {
    const Eigen::Vector3d& p = clouds[item.group].points[item.index].position;
    const double r = item.core ? o.radius : o.radius * o.outside_core_radii;
    const Eigen::Vector3d n = clouds[item.group].points[item.index].normal.cast<double>();
    const bool cylinder = !item.core && n.squaredNorm() > 0;
    const bool duplicate = std::any_of(kept.begin(), kept.end(), [&](const Item& k) {
      const Eigen::Vector3d d = clouds[k.group].points[k.index].position - p;
      if (k.group == item.group) return false;
      if (!cylinder) return d.squaredNorm() <= r * r;
      return std::abs(d.dot(n)) <= o.radius * o.surface_depth_radii &&
             d.squaredNorm() - d.dot(n) * d.dot(n) <= r * r;
    });
    if (!duplicate) kept.push_back(item);
  }
  std::sort(kept.begin(), kept.end(), [](const Item& a, const Item& b) {
    return a.group != b.group ? a.group < b.group : a.index < b.index;
  });
  ASSERT_EQ(merged.size(), kept.size());
  for (size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(merged[i].group, kept[i].group) << i;
    EXPECT_EQ(merged[i].index, kept[i].index) << i;
    EXPECT_EQ(merged[i].core, kept[i].core) << i;
  }
  // Duplicates occurred, and the lone group kept every point.
  EXPECT_GT(stats.duplicates, 20);
  EXPECT_EQ(stats.kept_by_group[2], 500);
}

TEST(CloudMerge, BadRadiusIsAnError) {
  PointCloud a;
  std::vector<GroupCloud> groups = {{&a, {0, 0}}};
  MergeOptions o;
  // Each field in turn: its bad values throw, then a good one is set.
  struct Case {
    double MergeOptions::*field;
    std::vector<double> bad;
    double good;
  };
  const std::vector<Case> cases = {
      {&MergeOptions::radius, {0.0, -1.0, std::nan("")}, 1},
      {&MergeOptions::outside_core_radii, {0.99, std::nan("")}, 1},
      {&MergeOptions::blend_radii, {-0.5, std::nan("")}, 0},
      {&MergeOptions::vote_zone_radii, {-1.0, std::nan("")}, 40},
      {&MergeOptions::vote_column_radii, {0.0, std::nan("")}, 6},
      {&MergeOptions::vote_reach_depths, {0.5}, 6},
  };
  for (const Case& c : cases) {
    for (const double bad : c.bad) {
      o.*c.field = bad;
      EXPECT_THROW(MergeGroupClouds(groups, o), Error) << bad;
    }
    o.*c.field = c.good;
  }
  EXPECT_NO_THROW(MergeGroupClouds(groups, o));
}

TEST(CloudMerge, CoreOwnerIsTheNearestCentre) {
  const std::vector<Eigen::Vector2d> centers = {{0, 0}, {10, 0}, {0, 10}};
  EXPECT_EQ(CoreOwner(centers, 1, 1), 0);
  EXPECT_EQ(CoreOwner(centers, 9, 1), 1);
  EXPECT_EQ(CoreOwner(centers, 1, 9), 2);
  EXPECT_EQ(CoreOwner({}, 1, 9), -1);
}

TEST(CloudMerge, CrossGroupPairsCountAsByBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 4);
  PointCloud c;
  std::vector<int> group_of;
  for (int i = 0; i < 601; ++i) {
    CloudPoint p;
    p.position = {500000.0 + u(rng), 5400000.0 + u(rng), 0.25 * u(rng)};
    c.points.push_back(p);
    group_of.push_back(i % 3);
  }
  for (const double r : {0.05, 0.2, 0.5}) {
    const long fast = CountCrossGroupPairs(c, group_of, r);
    EXPECT_EQ(fast, CrossGroupPairsWithin(c, group_of, r)) << r;
    if (r == 0.5) {
      EXPECT_GT(fast, 0);
    }
  }
  EXPECT_THROW(CountCrossGroupPairs(c, group_of, 0.0), Error);
  group_of.pop_back();
  EXPECT_THROW(CountCrossGroupPairs(c, group_of, 0.1), Error);
}

// Points on a lattice of the radius's own spacing, so that pairs lie at
// exactly the radius and on the grid's cube faces, at UTM-sized and at
// negative coordinates: the grid finds every pair the brute force does.
TEST(CloudMerge, PairsAtExactlyTheRadiusAreFoundAcrossCubeFaces) {
  for (const double origin : {500000.0, -37.0}) {
    PointCloud c;
    std::vector<int> group_of;
    const double r = 0.25;  // exact in binary, as are the lattice's offsets
    for (int i = 0; i < 7; ++i) {
      for (int j = 0; j < 7; ++j) {
        for (int k = 0; k < 3; ++k) {
          CloudPoint p;
          p.position = {origin + i * r, 5400000.0 + j * r, k * r};
          c.points.push_back(p);
          group_of.push_back((i + j + k) % 2);
        }
      }
    }
    const long brute = CrossGroupPairsWithin(c, group_of, r);
    EXPECT_GT(brute, 0);
    EXPECT_EQ(CountCrossGroupPairs(c, group_of, r), brute) << origin;
    // Each point of a sparser lattice has one partner, exactly the radius
    // below it along one axis: across a cube face for some of them.
    PointCloud a;
    for (int i = 0; i < 9; ++i) {
      CloudPoint p;
      p.position = {origin + 3 * r * i, 5400000.0 + 3 * r * (i % 3), 3 * r * (i % 2)};
      a.points.push_back(p);
    }
    for (int axis = 0; axis < 3; ++axis) {
      PointCloud below = a;
      for (CloudPoint& p : below.points) p.position[axis] -= r;
      EXPECT_EQ(CountWithNeighbour(a, below, r), static_cast<long>(a.points.size()))
          << origin << " axis " << axis;
    }
  }
}

TEST(CloudMerge, NeighbourCountIsAsByBruteForce) {
  PointCloud a, b;
  RandomPair(301, 3, 500000.0, &a, &b);
  for (const double r : {0.03, 0.1, 0.4}) {
    long expected = 0;
    for (const CloudPoint& p : a.points) {
      bool near = false;
      for (const CloudPoint& q : b.points) near |= (p.position - q.position).norm() <= r;
      expected += near;
    }
    EXPECT_EQ(CountWithNeighbour(a, b, r), expected) << r;
  }
  EXPECT_EQ(CountWithNeighbour(a, a, 1e-9), static_cast<long>(a.points.size()));
  EXPECT_EQ(CountWithNeighbour(a, PointCloud{}, 1.0), 0);
  EXPECT_THROW(CountWithNeighbour(a, b, 0.0), Error);
}

// A dense cloud on a plane that another samples every 3 units: every dense
// point is on the sampled surface though few lie within the tolerance of a
// sample; points off the plane, beyond the reach or next to samples without
// normals are not.
TEST(CloudMerge, SurfaceCountTakesTheSamplesTangentPlanes) {
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const Eigen::Vector3d u = n.cross(Eigen::Vector3d::UnitX()).normalized();
  const Eigen::Vector3d v = n.cross(u);
  const Eigen::Vector3d origin(500000.0, 5400000.0, 120.0);
  PointCloud sparse, dense, off, beyond;
  sparse.has_normals = true;
  for (int i = 0; i < 10; ++i) {
    for (int j = 0; j < 10; ++j) {
      CloudPoint p;
      p.position = origin + 3.0 * i * u + 3.0 * j * v;
      p.normal = n.cast<float>();
      sparse.points.push_back(p);
    }
  }
  for (int i = 0; i < 54; ++i) {
    for (int j = 0; j < 54; ++j) {
      CloudPoint p;
      p.position = origin + 0.5 * i * u + 0.5 * j * v;
      dense.points.push_back(p);
      p.position += 2.0 * n;
      off.points.push_back(p);
    }
  }
  CloudPoint far;
  far.position = origin - 5.0 * u;  // on the plane, 5 from the nearest sample
  beyond.points.push_back(far);
  const long all = static_cast<long>(dense.points.size());
  EXPECT_EQ(CountNearSurface(dense, sparse, 1.0, 4.0), all);
  EXPECT_LT(CountWithNeighbour(dense, sparse, 1.0), all / 2);
  EXPECT_EQ(CountNearSurface(off, sparse, 1.0, 4.0), 0);
  EXPECT_EQ(CountNearSurface(off, sparse, 2.5, 4.0), all);
  EXPECT_EQ(CountNearSurface(beyond, sparse, 1.0, 4.0), 0);
  EXPECT_EQ(CountNearSurface(beyond, sparse, 1.0, 5.5), 1);
  PointCloud no_plane = sparse;
  for (CloudPoint& p : no_plane.points) p.normal.setZero();
  EXPECT_EQ(CountNearSurface(dense, no_plane, 1.0, 4.0), 0);
  no_plane.has_normals = false;
  EXPECT_THROW(CountNearSurface(dense, no_plane, 1.0, 4.0), Error);
  EXPECT_THROW(CountNearSurface(dense, sparse, 5.0, 4.0), Error);
  EXPECT_THROW(CountNearSurface(dense, sparse, 0.0, 4.0), Error);
  EXPECT_EQ(CountNearSurface(dense, PointCloud{}, 1.0, 4.0), 0);
}

}  // namespace
}  // namespace sapmvs

#include "sapmvs/match/ground_region.h"

#include <gtest/gtest.h>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Three groups' centres in UTM-sized coordinates, as the run gives them.
const std::vector<Eigen::Vector2d> kCenters = {
    {500000.0, 5400000.0}, {500100.0, 5400000.0}, {500000.0, 5400060.0}};

TEST(GroundRegion, IsTheVoronoiCellOfItsCentre) {
  const GroundRegion r(kCenters, 0, 0);
  EXPECT_FALSE(r.Unbounded());
  EXPECT_TRUE(r.Contains({500049.0, 5400029.0}));
  EXPECT_FALSE(r.Contains({500051.0, 5400000.0}));  // nearer the second centre
  EXPECT_FALSE(r.Contains({500000.0, 5400031.0}));  // nearer the third
  EXPECT_TRUE(r.Contains({499000.0, 5399000.0}));   // beyond the block's edge: still its own
  // Every point lies in the region of its nearest centre, and only there.
  for (double x = 499950; x <= 500150; x += 7.3) {
    for (double y = 5399950; y <= 5400110; y += 6.1) {
      int in = 0, nearest = 0;
      for (int g = 0; g < 3; ++g) {
        in += GroundRegion(kCenters, g, 0).Contains({x, y});
        if ((kCenters[g] - Eigen::Vector2d(x, y)).norm() <
            (kCenters[nearest] - Eigen::Vector2d(x, y)).norm()) {
          nearest = g;
        }
      }
      EXPECT_EQ(in, 1) << x << " " << y;
      EXPECT_TRUE(GroundRegion(kCenters, nearest, 0).Contains({x, y})) << x << " " << y;
    }
  }
}

double PolygonArea(const std::vector<Eigen::Vector2d>& p) {
  double twice = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& a = p[i];
    const Eigen::Vector2d& b = p[(i + 1) % p.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return twice / 2;  // > 0 counter-clockwise
}

TEST(GroundRegion, OutlinesTileTheBox) {
  const Eigen::Vector2d lo(499950, 5399950), hi(500150, 5400110);
  double area = 0;
  for (int g = 0; g < 3; ++g) {
    const std::vector<Eigen::Vector2d> outline = GroundRegion(kCenters, g, 0).Outline(lo, hi);
    ASSERT_GE(outline.size(), 3u) << g;
    EXPECT_GT(PolygonArea(outline), 0) << g;
    area += PolygonArea(outline);
    // Its corners lie in the box and in the region (on its edges, within
    // rounding): the mean of the corners lies inside.
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& p : outline) {
      EXPECT_TRUE((p.array() >= lo.array() - 1e-6).all() && (p.array() <= hi.array() + 1e-6).all());
      EXPECT_TRUE(GroundRegion(kCenters, g, 1e-6).Contains(p)) << g << ": " << p.transpose();
      mean += p / outline.size();
    }
    EXPECT_TRUE(GroundRegion(kCenters, g, 0).Contains(mean)) << g;
  }
  EXPECT_NEAR(area, (hi - lo).prod(), 1e-3);
  // One group: the whole box; a box beyond a region: nothing.
  EXPECT_NEAR(PolygonArea(GroundRegion().Outline(lo, hi)), (hi - lo).prod(), 1e-6);
  EXPECT_TRUE(GroundRegion(kCenters, 0, 0).Outline({500080, 5399950}, {500150, 5400000}).empty());
}

TEST(GroundRegion, TheMarginReachesIntoTheNeighboursGround) {
  const GroundRegion r(kCenters, 0, 5);
  EXPECT_TRUE(r.Contains({500054.9, 5400000.0}));
  EXPECT_FALSE(r.Contains({500055.1, 5400000.0}));
  EXPECT_TRUE(r.Contains({500000.0, 5400034.9}));
  EXPECT_FALSE(r.Contains({500000.0, 5400035.1}));
}

TEST(GroundRegion, OneGroupOrNoneOwnsEverything) {
  EXPECT_TRUE(GroundRegion().Unbounded());
  EXPECT_TRUE(GroundRegion().Contains({1e9, -1e9}));
  const GroundRegion alone({{10.0, 20.0}}, 0, 0);
  EXPECT_TRUE(alone.Unbounded());
  // A centre shared with another group gives no bisector.
  const GroundRegion twin({{10.0, 20.0}, {10.0, 20.0}}, 1, 0);
  EXPECT_TRUE(twin.Unbounded());
}

TEST(GroundRegion, RefusesAnIndexOutsideOrANegativeMargin) {
  EXPECT_THROW(GroundRegion(kCenters, 3, 0), Error);
  EXPECT_THROW(GroundRegion(kCenters, -1, 0), Error);
  EXPECT_THROW(GroundRegion(kCenters, 0, -1), Error);
}

}  // namespace
}  // namespace sapmvs

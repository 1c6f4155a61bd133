#include "sapmvs/run/core_index.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "sapmvs/run/cloud_merge.h"

namespace sapmvs {
namespace {

// Jittered grid centres at UTM-sized coordinates, two of them the same,
// and points over and well beyond their extent.
struct CoreIndexCase {
  std::vector<Eigen::Vector2d> centers;
  std::vector<Eigen::Vector2d> points;
};

CoreIndexCase MakeCoreIndexCase(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-30, 30);
  CoreIndexCase c;
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 9; ++x)
      c.centers.emplace_back(500000 + 100 * x + jitter(rng), 5400000 + 120 * y + jitter(rng));
  c.centers.push_back(c.centers[20]);
  std::uniform_real_distribution<double> px(499500, 501400), py(5399500, 5401300);
  for (int i = 0; i < 20000; ++i) c.points.emplace_back(px(rng), py(rng));
  // On a bisector: equidistant from two centres, where ties decide.
  c.points.push_back(0.5 * (c.centers[3] + c.centers[4]));
  return c;
}

// Owner, border within reach, and the two nearest centres where their
// border lies within reach, as CoreOwner and CoreOwnerAndBorder find them
// against every centre.
TEST(CoreIndex, AgreesWithEveryCentreWithinItsReach) {
  for (const unsigned seed : {1u, 2u}) {
    for (const double reach : {0.0, 3.0, 45.0}) {
      const CoreIndexCase c = MakeCoreIndexCase(seed);
      const CoreIndex grid(c.centers, reach, {500000, 5400000}, {500800, 5400720});
      const CoreIndex around(c.centers, reach);
      long near_border = 0;
      for (const Eigen::Vector2d& p : c.points) {
        const auto [own, border] = CoreOwnerAndBorder(c.centers, p.x(), p.y());
        for (const CoreIndex* index : {&grid, &around}) {
          ASSERT_EQ(index->Owner(p), own) << p.transpose() << " reach " << reach;
          const auto [own2, border2] = index->OwnerAndBorder(p);
          ASSERT_EQ(own2, own);
          if (border <= reach) {
            ASSERT_EQ(border2, border) << p.transpose() << " reach " << reach;
          } else {
            ASSERT_GT(border2, reach) << p.transpose() << " reach " << reach;
          }
          // The next nearest, by every centre.
          int next = -1;
          for (int g = 0; g < static_cast<int>(c.centers.size()); ++g) {
            if (g == own) continue;
            if (next < 0 || (p - c.centers[g]).squaredNorm() < (p - c.centers[next]).squaredNorm())
              next = g;
          }
          const auto [first, second] = index->TwoNearest(p);
          ASSERT_EQ(first, own);
          const double next_border = BeyondBisector(c.centers[own], c.centers[next], p);
          if (std::abs(next_border) <= reach) {
            ASSERT_EQ(second, next) << p.transpose() << " reach " << reach;
          } else if (second >= 0) {
            ASSERT_GT(std::abs(BeyondBisector(c.centers[own], c.centers[second], p)), reach);
          }
        }
        near_border += border <= reach;
      }
      if (reach > 0) {
        EXPECT_GT(near_border, 100) << "reach " << reach;
      }
    }
  }
}

TEST(CoreIndex, FewCentresOrNone) {
  const CoreIndex none({}, 1.0);
  EXPECT_EQ(none.Owner({1, 2}), -1);
  EXPECT_EQ(none.OwnerAndBorder({1, 2}).first, -1);
  EXPECT_EQ(none.TwoNearest({1, 2}), std::make_pair(-1, -1));
  const CoreIndex one({{0, 0}}, 1.0);
  EXPECT_EQ(one.Owner({5, 5}), 0);
  EXPECT_TRUE(std::isinf(one.OwnerAndBorder({5, 5}).second));
  EXPECT_EQ(one.TwoNearest({5, 5}), std::make_pair(0, -1));
  const CoreIndex two({{0, 0}, {10, 0}}, 1.0);
  EXPECT_EQ(two.OwnerAndBorder({4, 3}), std::make_pair(0, 1.0));
  EXPECT_EQ(two.TwoNearest({7, 0}), std::make_pair(1, 0));
}

}  // namespace
}  // namespace sapmvs

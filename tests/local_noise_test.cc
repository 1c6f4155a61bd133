#include "sapmvs/evaluate/local_noise.h"

#include <gtest/gtest.h>

#include <random>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// A tilted plane sampled every `spacing` over `side` x `side`, heights
// offset by Gaussian noise of `sigma` (0: none) and by `layer` on every
// second point: two surfaces stacked, as two groups' clouds that disagree.
PointCloud Plane(double side, double spacing, double sigma, double layer = 0) {
  PointCloud c;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  long k = 0;
  // Far from the origin: the fit must keep its digits at UTM coordinates.
  const Eigen::Vector3d at(500000, 4000000, 300);
  for (double x = 0; x < side; x += spacing) {
    for (double y = 0; y < side; y += spacing) {
      CloudPoint p;
      double z = 0.3 * x - 0.1 * y + (sigma > 0 ? noise(rng) : 0);
      if (k++ % 2) z += layer;
      p.position = at + Eigen::Vector3d(x, y, z);
      c.points.push_back(p);
    }
  }
  return c;
}

LocalNoiseOptions Options(double radius) {
  LocalNoiseOptions o;
  o.radius = radius;
  o.samples = 5000;
  return o;
}

TEST(LocalNoise, IsZeroOnAPlaneAndItsNoiseOnANoisyOne) {
  const LocalNoise flat = MeasureLocalNoise(Plane(20, 0.1, 0), Options(0.4));
  EXPECT_EQ(flat.sampled, 5000);
  EXPECT_LT(flat.median, 1e-6);
  EXPECT_LT(flat.p90, 1e-6);
  // Noise sigma along z on a plane 17 degrees steep: a point's distance to
  // the fitted plane is about sigma cos(17 deg) sqrt(1 + 1/12), whose median
  // is 0.67 of that and whose 90th percentile 1.64.
  const double sigma = 0.02;
  const LocalNoise noisy = MeasureLocalNoise(Plane(20, 0.1, sigma), Options(0.4));
  const double s = sigma * std::cos(std::atan(std::hypot(0.3, 0.1))) * std::sqrt(1 + 1.0 / 12);
  EXPECT_NEAR(noisy.median, 0.674 * s, 0.15 * 0.674 * s);
  EXPECT_NEAR(noisy.p90, 1.645 * s, 0.2 * 1.645 * s);
}

TEST(LocalNoise, SeesTwoStackedSurfaces) {
  const double sigma = 0.01;
  const LocalNoise one = MeasureLocalNoise(Plane(20, 0.1, sigma), Options(0.4));
  const LocalNoise two = MeasureLocalNoise(Plane(20, 0.1, sigma, 0.05), Options(0.4));
  EXPECT_GT(two.median, 1.8 * one.median);
}

TEST(LocalNoise, SkipsPointsWithTooFewNeighbours) {
  // Points 1 apart with a radius of 1.5: 8 neighbours each inside, fewer on
  // the rim; at least 9 asked for, none qualifies.
  LocalNoiseOptions o = Options(1.5);
  o.min_neighbours = 9;
  EXPECT_EQ(MeasureLocalNoise(Plane(10, 1, 0), o).sampled, 0);
  o.min_neighbours = 8;
  EXPECT_EQ(MeasureLocalNoise(Plane(10, 1, 0), o).sampled, 64);
}

TEST(LocalNoise, RefusesBadOptions) {
  EXPECT_THROW(MeasureLocalNoise(Plane(1, 0.1, 0), Options(0)), Error);
  LocalNoiseOptions o = Options(1);
  o.min_neighbours = 2;
  EXPECT_THROW(MeasureLocalNoise(Plane(1, 0.1, 0), o), Error);
}

TEST(GroundCover, CountsCellsHoldingAPoint) {
  const PointCloud c = Plane(10, 1, 0);  // 10 x 10 points, 1 apart
  EXPECT_EQ(CoveredCells(c, 1).size(), 100u);
  EXPECT_EQ(CoveredCells(c, 2).size(), 25u);
  EXPECT_THROW(CoveredCells(c, 0), Error);
}

}  // namespace
}  // namespace sapmvs

#include "match/group_data.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace sapmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(TriangulationAngleDeg, KnownAngles) {
  const Eigen::Vector3d x(0, 0, 0);
  EXPECT_NEAR(TriangulationAngleDeg({1, 0, 0}, {0, 1, 0}, x), 90.0, 1e-12);
  EXPECT_NEAR(TriangulationAngleDeg({5, 0, 0}, {-7, 0, 0}, x), 180.0, 1e-12);
  EXPECT_NEAR(TriangulationAngleDeg({3, 3, 3}, {1, 1, 1}, x), 0.0, 1e-5);
  EXPECT_NEAR(TriangulationAngleDeg({1, 0, 0}, {1, 1, 0}, x), 45.0, 1e-12);
  // Two cameras 100 up, 2 h tan(15 deg) apart, see the point between them at 30 degrees.
  const double half = 100 * std::tan(15.0 * kPi / 180.0);
  EXPECT_NEAR(TriangulationAngleDeg({512000 - half, 5405000, 400}, {512000 + half, 5405000, 400},
                                    {512000, 5405000, 300}),
              30.0, 1e-9);
}

TEST(TriangulationAngleDeg, SymmetricAndIndependentOfDistanceAlongTheRays) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(-1, 1), scale(0.1, 10);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d x(100 * unit(rng), 100 * unit(rng), 10 * unit(rng));
    const Eigen::Vector3d da = Eigen::Vector3d(unit(rng), unit(rng), 1).normalized();
    const Eigen::Vector3d db = Eigen::Vector3d(unit(rng), unit(rng), 1).normalized();
    const double expected = std::acos(da.dot(db)) * 180.0 / kPi;
    const double got = TriangulationAngleDeg(x + 50 * da, x + 80 * db, x);
    EXPECT_NEAR(got, expected, 1e-9) << "trial " << trial;
    EXPECT_NEAR(TriangulationAngleDeg(x + 80 * db, x + 50 * da, x), got, 1e-12);
    EXPECT_NEAR(TriangulationAngleDeg(x + scale(rng) * da, x + scale(rng) * db, x), got, 1e-9);
  }
}

}  // namespace
}  // namespace sapmvs

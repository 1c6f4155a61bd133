#include "match/seed_matcher.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <random>

#include "sapmvs/block/camera.h"

namespace sapmvs {
namespace {

// A camera about `height` above `target` looking roughly down at it.
Camera LookingDown(std::mt19937& rng, const Eigen::Vector3d& offset, double height) {
  std::uniform_real_distribution<double> tilt(-15, 15), kappa(-180, 180), pos(-60, 60);
  const Intrinsics k = Intrinsics::FromPixels(1000, 1003, 639.5 + 3.0, 479.5 - 2.0, 1280, 960);
  return Camera::FromAngles(k, offset + Eigen::Vector3d(pos(rng), pos(rng), height), tilt(rng),
                            tilt(rng), kappa(rng), AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
}

// Recovers points seen in two random cameras, exactly up to rounding:
// relative to the distance from camera a.
void ExpectRecoversProjectedPoints(const Eigen::Vector3d& offset, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ground(-40, 40), relief(-10, 10);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Camera a = LookingDown(rng, offset, 200);
    const Camera b = LookingDown(rng, offset, 210);
    const Eigen::Vector3d x = offset + Eigen::Vector3d(ground(rng), ground(rng), relief(rng));
    const Eigen::Vector2d uv_a = a.Project(x), uv_b = b.Project(x);
    if (!uv_a.allFinite() || !uv_b.allFinite()) continue;
    // Nearly parallel rays would measure the conditioning, not the method.
    if ((a.center() - b.center()).norm() < 20) continue;
    ++tested;
    const Eigen::Vector3d got = TriangulateMidpoint(a, uv_a, b, uv_b);
    ASSERT_TRUE(got.allFinite()) << "trial " << trial;
    EXPECT_LE((got - x).norm(), 1e-9 * (x - a.center()).norm())
        << "trial " << trial << ": got (" << got.transpose() << "), expected (" << x.transpose()
        << ")";
  }
  EXPECT_GT(tested, 100);
}

TEST(TriangulateMidpoint, RecoversAKnownPointLocalFrame) {
  ExpectRecoversProjectedPoints(Eigen::Vector3d::Zero(), 11);
}

TEST(TriangulateMidpoint, RecoversAKnownPointUtmCoordinates) {
  ExpectRecoversProjectedPoints(Eigen::Vector3d(512345.0, 5405678.0, 300.0), 12);
}

TEST(TriangulateMidpoint, SkewRaysGiveTheMidpointOfTheCommonPerpendicular) {
  // Through their principal points, camera a's ray is the z axis and camera
  // b's the line y = 2, z = 4 along +x: they miss each other by 2, closest at
  // (0, 0, 4) and (0, 2, 4).
  const Intrinsics k = Intrinsics::FromPixels(500, 500, 200, 150, 401, 301);
  const Camera a(k, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  Eigen::Matrix3d r_wc;  // rows: the camera's x, y, z axes in the world
  r_wc.row(0) = Eigen::Vector3d(0, 0, -1);
  r_wc.row(1) = Eigen::Vector3d(0, 1, 0);
  r_wc.row(2) = Eigen::Vector3d(1, 0, 0);
  const Camera b(k, r_wc, Eigen::Vector3d(-10, 2, 4));
  const Eigen::Vector3d got =
      TriangulateMidpoint(a, Eigen::Vector2d(200, 150), b, Eigen::Vector2d(200, 150));
  EXPECT_LE((got - Eigen::Vector3d(0, 1, 4)).norm(), 1e-12) << got.transpose();
}

TEST(TriangulateMidpoint, IdenticalRaysAreNotFinite) {
  std::mt19937 rng(13);
  const Camera a = LookingDown(rng, Eigen::Vector3d::Zero(), 200);
  const Eigen::Vector3d got =
      TriangulateMidpoint(a, Eigen::Vector2d(300, 200), a, Eigen::Vector2d(300, 200));
  EXPECT_FALSE(got.allFinite()) << got.transpose();
}

TEST(TriangulateMidpoint, ParallelRaysFromTwoCentresAreNotFinite) {
  // Same orientation, camera b moved sideways: the same pixel's rays are
  // parallel and never meet.
  std::mt19937 rng(14);
  const Camera a = LookingDown(rng, Eigen::Vector3d::Zero(), 200);
  const Camera b(a.intrinsics(), a.rotation(), a.center() + Eigen::Vector3d(30, -5, 2));
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(639.5, 479.5), Eigen::Vector2d(10, 900)}) {
    const Eigen::Vector3d got = TriangulateMidpoint(a, uv, b, uv);
    EXPECT_FALSE(got.allFinite()) << "uv (" << uv.transpose() << "): " << got.transpose();
  }
}

}  // namespace
}  // namespace sapmvs

#include "match/propagation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "sapmvs/block/camera.h"

namespace sapmvs {
namespace {

Camera TiltedCamera(std::mt19937& rng, const Eigen::Vector3d& offset) {
  std::uniform_real_distribution<double> tilt(-25, 25), kappa(-180, 180), pos(-30, 30);
  const Intrinsics k = Intrinsics::FromPixels(800, 805, 320.5, 238.0, 641, 481);
  return Camera::FromAngles(k, offset + Eigen::Vector3d(pos(rng), pos(rng), 120 + pos(rng)),
                            tilt(rng), tilt(rng), kappa(rng), AngleOrder::kOmegaPhiKappa,
                            AngleUnit::kDegree);
}

bool AllNan(const Eigen::Vector3d& x) {
  return std::isnan(x.x()) && std::isnan(x.y()) && std::isnan(x.z());
}

// A random plane through a point near the ground under the camera, tilted by
// up to 60 degrees, and a point on it in front of the camera.
void ExpectReturnsThePointOnThePlane(const Eigen::Vector3d& offset, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1), along(-15, 15);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Camera camera = TiltedCamera(rng, offset);
    const Eigen::Vector3d c =
        offset + Eigen::Vector3d(10 * unit(rng), 10 * unit(rng), 5 * unit(rng));
    const Eigen::Vector3d n =
        (Eigen::AngleAxisd(1.05 * unit(rng),
                           Eigen::Vector3d(unit(rng), unit(rng), 0).normalized()) *
         Eigen::Vector3d::UnitZ())
            .normalized();
    // Two directions in the plane.
    const Eigen::Vector3d t1 = n.unitOrthogonal();
    const Eigen::Vector3d t2 = n.cross(t1);
    const Eigen::Vector3d x = c + along(rng) * t1 + along(rng) * t2;
    const Eigen::Vector2d uv = camera.Project(x);
    if (!uv.allFinite()) continue;
    // Grazing rays would measure the conditioning, not the method.
    if (std::abs(n.dot(camera.Ray(uv))) < 0.2) continue;
    ++tested;
    const Eigen::Vector3d got = IntersectPlane(camera, uv, c, n);
    ASSERT_TRUE(got.allFinite()) << "trial " << trial;
    EXPECT_LE((got - x).norm(), 1e-9 * (x - camera.center()).norm())
        << "trial " << trial << ": got (" << got.transpose() << "), expected (" << x.transpose()
        << ")";
    // The plane's normal may point either way.
    EXPECT_LE((IntersectPlane(camera, uv, c, -n) - x).norm(), 1e-9 * (x - camera.center()).norm());
  }
  EXPECT_GT(tested, 100);
}

TEST(IntersectPlane, ReturnsThePointWhoseProjectionTheRayPassesThrough) {
  ExpectReturnsThePointOnThePlane(Eigen::Vector3d::Zero(), 21);
}

TEST(IntersectPlane, ReturnsThePointInUtmCoordinates) {
  ExpectReturnsThePointOnThePlane(Eigen::Vector3d(512345.0, 5405678.0, 300.0), 22);
}

TEST(IntersectPlane, HorizontalGroundUnderANadirCamera) {
  // Nadir camera 100 above z = 0: the principal point sees the ground right
  // below, and pixel (cx + 80, cy) sees 10 further along +x (f = 800).
  Eigen::Matrix3d r_wc;
  r_wc.row(0) = Eigen::Vector3d(1, 0, 0);
  r_wc.row(1) = Eigen::Vector3d(0, -1, 0);
  r_wc.row(2) = Eigen::Vector3d(0, 0, -1);
  const Camera camera(Intrinsics::FromPixels(800, 800, 320, 240, 641, 481), r_wc,
                      Eigen::Vector3d(5, 7, 100));
  const Eigen::Vector3d c(-3, 4, 0), n(0, 0, 1);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(320, 240), c, n) - Eigen::Vector3d(5, 7, 0)).norm(),
      1e-12);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(400, 240), c, n) - Eigen::Vector3d(15, 7, 0)).norm(),
      1e-12);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(320, 160), c, n) - Eigen::Vector3d(5, 17, 0)).norm(),
      1e-12);
}

TEST(IntersectPlane, PlaneParallelToTheRayIsNan) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = TiltedCamera(rng, Eigen::Vector3d::Zero());
    const Eigen::Vector2d uv(100 + 20 * trial, 50 + 15 * trial);
    const Eigen::Vector3d ray = camera.Ray(uv);
    // A plane containing the ray's direction, off the ray and through it.
    const Eigen::Vector3d n = ray.unitOrthogonal();
    const Eigen::Vector3d off = camera.center() - 50 * n + 80 * ray;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, off, n))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, camera.center() + 80 * ray, n)))
        << "trial " << trial;
  }
}

TEST(IntersectPlane, PlaneBehindTheCameraIsNan) {
  std::mt19937 rng(24);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = TiltedCamera(rng, Eigen::Vector3d::Zero());
    const Eigen::Vector2d uv(100 + 20 * trial, 50 + 15 * trial);
    const Eigen::Vector3d ray = camera.Ray(uv);
    // The ray's line meets these planes 40 behind the centre.
    const Eigen::Vector3d behind = camera.center() - 40 * ray;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, ray))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, -ray))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, Eigen::Vector3d::UnitZ())))
        << "trial " << trial;
    // The same plane moved in front of the camera is hit.
    const Eigen::Vector3d ahead = camera.center() + 40 * ray;
    EXPECT_LE((IntersectPlane(camera, uv, ahead, ray) - ahead).norm(), 1e-9) << "trial " << trial;
  }
}

}  // namespace
}  // namespace sapmvs

#include "match/plane_refit.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "sapmvs/block/camera.h"

namespace sapmvs {
namespace {

// One nadir camera 100 m above the ground z = 0 (local frame), 640 x 480
// px, f = 300 px: a footprint of 1/3 m on the ground.
MatchGroupData NadirGroup() {
  Eigen::Matrix3d r_wc;
  r_wc.row(0) = Eigen::Vector3d(1, 0, 0);
  r_wc.row(1) = Eigen::Vector3d(0, -1, 0);
  r_wc.row(2) = Eigen::Vector3d(0, 0, -1);
  MatchGroupData group;
  MatchImage im;
  im.camera = Camera(Intrinsics::FromPixels(300, 300, 319.5, 239.5, 640, 480), r_wc,
                     Eigen::Vector3d(0, 0, 100));
  group.images.push_back(im);
  return group;
}

constexpr double kFootprint = 100.0 / 300.0;

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(std::abs(a.normalized().dot(b.normalized())), 0.0, 1.0)) * 180 / M_PI;
}

// Patches of `size` px on a grid `step` px apart on the plane z = z0 + slope
// x (local frame), each with its normal tilted `tilt_deg` off the truth about
// a random axis in the plane, and its centre up to `noise` footprints off the
// plane.
void AddPlane(std::vector<AcceptedPatch>* patches, double x0, double x1, double z0, double slope,
              int size, double step, double tilt_deg, double noise, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1, 1);
  const Eigen::Vector3d truth = Eigen::Vector3d(-slope, 0, 1).normalized();
  for (double x = x0; x <= x1 + 1e-9; x += step * kFootprint) {
    for (double y = -10; y <= 10 + 1e-9; y += step * kFootprint) {
      AcceptedPatch p;
      const Eigen::Vector3d axis = truth.cross(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
      p.center = Eigen::Vector3d(x, y, z0 + slope * x) + noise * kFootprint * unit(rng) * truth;
      p.normal = Eigen::AngleAxisd(tilt_deg * M_PI / 180, axis.normalized()) * truth;
      p.ref = 0;
      p.size = size;
      patches->push_back(p);
    }
  }
}

TEST(FitPatchNormals, RecoversATiltedPlaneFromNeighboursWithBadNormals) {
  std::mt19937 rng(7);
  std::vector<AcceptedPatch> patches;
  // 7 x 7 patches 5 px apart (the propagation's step), normals 6 degrees
  // off (their next neighbours' centres then lie up to 0.6 footprints off
  // their planes, within refit_tolerance), centres within a tenth of a
  // footprint of a 10 % slope.
  AddPlane(&patches, -10, 10, 0, 0.1, 7, 5, 6, 0.1, rng);
  MatcherOptions options;
  const std::vector<Eigen::Vector3d> fitted =
      FitPatchNormals(NadirGroup(), options, patches, std::vector<uint8_t>(patches.size(), 1));
  const Eigen::Vector3d truth = Eigen::Vector3d(-0.1, 0, 1).normalized();
  int checked = 0;
  for (size_t p = 0; p < patches.size(); ++p) {
    EXPECT_NEAR(AngleDeg(patches[p].normal, truth), 6, 1e-6);
    ASSERT_FALSE(fitted[p].isZero()) << "patch " << p;
    EXPECT_NEAR(fitted[p].norm(), 1, 1e-12);
    // Faces the camera above.
    EXPECT_GT(fitted[p].z(), 0);
    EXPECT_LT(AngleDeg(fitted[p], truth), 2.0) << "patch " << p;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(FitPatchNormals, AStepKeepsEachSideToItsOwnPlane) {
  // Ground z = 0 for x < 0 and a flat roof 3 m (9 footprints) up for x > 0,
  // whose patches' normals lean 8 degrees toward each other. The centres
  // of the other level must not take part: fitted with them, the patches next
  // to the step would tilt by tens of degrees.
  std::mt19937 rng(11);
  std::vector<AcceptedPatch> patches;
  AddPlane(&patches, -10, -0.5, 0, 0, 7, 5, 8, 0.1, rng);
  AddPlane(&patches, 0.5, 10, 3, 0, 7, 5, 8, 0.1, rng);
  MatcherOptions options;
  const std::vector<Eigen::Vector3d> fitted =
      FitPatchNormals(NadirGroup(), options, patches, std::vector<uint8_t>(patches.size(), 1));
  for (size_t p = 0; p < patches.size(); ++p) {
    if (fitted[p].isZero()) continue;
    EXPECT_LT(AngleDeg(fitted[p], Eigen::Vector3d::UnitZ()), 2.0)
        << "patch " << p << " at (" << patches[p].center.transpose() << ")";
  }
  int fitted_count = 0;
  for (const Eigen::Vector3d& n : fitted) fitted_count += !n.isZero();
  EXPECT_GT(fitted_count, static_cast<int>(patches.size()) * 9 / 10);
}

TEST(FitPatchNormals, LeavesUnconfirmedPatchesUnfitted) {
  std::mt19937 rng(3);
  std::vector<AcceptedPatch> patches;
  // A row along x: collinear centres leave the plane free to turn about it.
  for (int i = 0; i < 12; ++i) {
    AcceptedPatch p;
    p.center = Eigen::Vector3d(i * 5 * kFootprint, 0, 0);
    p.normal = Eigen::Vector3d::UnitZ();
    p.ref = 0;
    p.size = 7;
    patches.push_back(p);
  }
  // Two lone patches far from everything.
  for (const double x : {-40.0, 40.0}) {
    AcceptedPatch p;
    p.center = Eigen::Vector3d(x, 20, 0);
    p.normal = Eigen::Vector3d::UnitZ();
    p.ref = 0;
    p.size = 21;
    patches.push_back(p);
  }
  MatcherOptions options;
  const MatchGroupData group = NadirGroup();
  std::vector<Eigen::Vector3d> fitted =
      FitPatchNormals(group, options, patches, std::vector<uint8_t>(patches.size(), 1));
  for (size_t p = 0; p < patches.size(); ++p) EXPECT_TRUE(fitted[p].isZero()) << "patch " << p;

  // A full plane fits; with refit_neighbours = 0, or with its patches not
  // alive, nothing is fitted.
  patches.clear();
  AddPlane(&patches, -5, 5, 0, 0, 7, 5, 5, 0.1, rng);
  fitted = FitPatchNormals(group, options, patches, std::vector<uint8_t>(patches.size(), 1));
  EXPECT_FALSE(fitted[patches.size() / 2].isZero());
  std::vector<uint8_t> alive(patches.size(), 1);
  for (size_t p = 0; p < patches.size(); ++p) alive[p] = p == patches.size() / 2;
  fitted = FitPatchNormals(group, options, patches, alive);
  for (size_t p = 0; p < patches.size(); ++p) EXPECT_TRUE(fitted[p].isZero()) << "patch " << p;
  options.refit_neighbours = 0;
  fitted = FitPatchNormals(group, options, patches, std::vector<uint8_t>(patches.size(), 1));
  for (size_t p = 0; p < patches.size(); ++p) EXPECT_TRUE(fitted[p].isZero()) << "patch " << p;
}

TEST(FitPatchNormals, AFittedPlaneThatFacesAwayIsRejected) {
  // A wall x = 0 seen from straight above: a plane the view angle (60
  // degrees) excludes, however well its centres fit.
  std::vector<AcceptedPatch> patches;
  for (int i = -5; i <= 5; ++i) {
    for (int j = -5; j <= 5; ++j) {
      AcceptedPatch p;
      p.center = Eigen::Vector3d(0, i * 5 * kFootprint, 5 + j * 5 * kFootprint);
      p.normal = Eigen::Vector3d(1, 0, 1).normalized();
      p.ref = 0;
      p.size = 7;
      patches.push_back(p);
    }
  }
  MatcherOptions options;
  options.refit_tolerance = 100;  // every neighbour confirms
  const std::vector<Eigen::Vector3d> fitted =
      FitPatchNormals(NadirGroup(), options, patches, std::vector<uint8_t>(patches.size(), 1));
  for (size_t p = 0; p < patches.size(); ++p) EXPECT_TRUE(fitted[p].isZero()) << "patch " << p;
}

}  // namespace
}  // namespace sapmvs

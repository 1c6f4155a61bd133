#include "sapmvs/evaluate/surface_check.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// A flat surface at height 10: 200 x 200 cells of 0.5, i.e. x in [1000, 1100]
// and y in [2000, 2100].
constexpr double kX0 = 1000, kY0 = 2100, kZ = 10;
constexpr int kRasterCells = 200;
constexpr double kRasterCell = 0.5;
// The check's cells: 2 x 2, i.e. 50 x 50 of them over the raster.
constexpr double kCell = 2.0;
constexpr int kCheckCells = 50;
constexpr double kTolerance = 0.3;

GeoRaster FlatSurface() {
  GeoRaster r;
  r.width = r.height = kRasterCells;
  r.origin_x = kX0;
  r.origin_y = kY0;
  r.cell_size = kRasterCell;
  r.values.assign(static_cast<size_t>(kRasterCells) * kRasterCells, static_cast<float>(kZ));
  return r;
}

// Nadir pinhole cameras 100 above the surface near its centre; each image
// (400 x 400 px, f = 150 px) covers 267 x 267, so every camera sees it all.
Block NadirBlock(int num_cameras) {
  Block block;
  block.format = "yaml";
  Eigen::Matrix3d r_wc;
  r_wc.row(0) = Eigen::Vector3d(1, 0, 0);
  r_wc.row(1) = Eigen::Vector3d(0, -1, 0);
  r_wc.row(2) = Eigen::Vector3d(0, 0, -1);
  const Intrinsics k = Intrinsics::FromPixels(150, 150, 199.5, 199.5, 400, 400);
  for (int i = 0; i < num_cameras; ++i) {
    BlockImage im;
    im.name = "IMG_" + std::to_string(i);
    im.camera_name = "cam";
    im.camera = Camera(k, r_wc, Eigen::Vector3d(1045 + 5 * i, 2048 + 2 * (i % 2), kZ + 100));
    block.images.push_back(im);
  }
  block.origin = ChooseLocalOrigin(block.images);
  return block;
}

// One point at the centre of every check cell, on the surface.
PointCloud PointPerCell() {
  PointCloud cloud;
  for (int r = 0; r < kCheckCells; ++r) {
    for (int c = 0; c < kCheckCells; ++c) {
      CloudPoint p;
      p.position = {kX0 + (c + 0.5) * kCell, kY0 - (r + 0.5) * kCell, kZ};
      cloud.points.push_back(p);
    }
  }
  return cloud;
}

SurfaceCheckOptions Options() {
  SurfaceCheckOptions o;
  o.tolerance = kTolerance;
  o.cell_size = kCell;
  o.min_images = 3;
  return o;
}

TEST(CheckAgainstSurface, PointsOnTheSurfaceEverywhereAreAllWithinAndCoverAll) {
  const PointCloud cloud = PointPerCell();
  const SurfaceCheck s = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), Options());
  EXPECT_EQ(s.points, kCheckCells * kCheckCells);
  EXPECT_EQ(s.checked, kCheckCells * kCheckCells);
  EXPECT_EQ(s.within, kCheckCells * kCheckCells);
  EXPECT_EQ(s.share_within, 1.0);
  EXPECT_EQ(s.median_abs_dz, 0.0);
  // Flat and seen by all three cameras: every cell is seen.
  EXPECT_EQ(s.cells_seen, kCheckCells * kCheckCells);
  EXPECT_EQ(s.cells_covered, s.cells_seen);
  EXPECT_EQ(s.coverage, 1.0);
}

TEST(CheckAgainstSurface, HalfThePointsTwoTolerancesUpHalveShareAndCoverage) {
  PointCloud cloud = PointPerCell();
  for (size_t i = 0; i < cloud.points.size(); i += 2)
    cloud.points[i].position.z() += 2 * kTolerance;
  const SurfaceCheck s = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), Options());
  EXPECT_EQ(s.checked, kCheckCells * kCheckCells);
  EXPECT_EQ(s.within, kCheckCells * kCheckCells / 2);
  EXPECT_EQ(s.share_within, 0.5);
  // Half are at 0, half at 2 tolerances: the median is one or the other.
  EXPECT_TRUE(s.median_abs_dz == 0.0 || std::abs(s.median_abs_dz - 2 * kTolerance) < 1e-6)
      << s.median_abs_dz;
  // A cell whose only point is off the surface is not covered.
  EXPECT_EQ(s.cells_seen, kCheckCells * kCheckCells);
  EXPECT_EQ(s.cells_covered, kCheckCells * kCheckCells / 2);
  EXPECT_EQ(s.coverage, 0.5);
}

TEST(CheckAgainstSurface, ARegionCountsOnlyItsPointsAndCells) {
  // The left half (x < 1050) is off the surface, the right half on it: each
  // region sees only its own half.
  PointCloud cloud = PointPerCell();
  for (CloudPoint& p : cloud.points) {
    if (p.position.x() < 1050) p.position.z() += 2 * kTolerance;
  }
  SurfaceCheckOptions o = Options();
  o.region = [](double x, double) { return x < 1050; };
  const SurfaceCheck left = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), o);
  o.region = [](double x, double) { return x >= 1050; };
  const SurfaceCheck right = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), o);
  const long half = kCheckCells * kCheckCells / 2;
  EXPECT_EQ(left.checked, half);
  EXPECT_EQ(left.within, 0);
  EXPECT_EQ(left.cells_seen, half);
  EXPECT_EQ(left.cells_covered, 0);
  EXPECT_EQ(right.checked, half);
  EXPECT_EQ(right.within, half);
  EXPECT_EQ(right.cells_seen, half);
  EXPECT_EQ(right.coverage, 1.0);
}

TEST(CheckAgainstSurface, PointsJustInsideTheToleranceCount) {
  PointCloud cloud = PointPerCell();
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    cloud.points[i].position.z() += (i % 2 == 0 ? 0.9 : -0.9) * kTolerance;
  }
  const SurfaceCheck s = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), Options());
  EXPECT_EQ(s.share_within, 1.0);
  EXPECT_NEAR(s.median_abs_dz, 0.9 * kTolerance, 1e-6);
  EXPECT_EQ(s.coverage, 1.0);
}

TEST(CheckAgainstSurface, RemovingTheCellsOfAKnownSetLowersCoverageByItsShare) {
  // Drop the points of the 12 leftmost columns of cells and of a 5 x 7 patch
  // elsewhere; add a second point to some remaining cells (no effect on
  // coverage) and points outside the surface (not checked).
  PointCloud cloud;
  long removed = 0;
  for (const CloudPoint& p : PointPerCell().points) {
    const int c = static_cast<int>(std::floor((p.position.x() - kX0) / kCell));
    const int r = static_cast<int>(std::floor((kY0 - p.position.y()) / kCell));
    if (c < 12 || (c >= 30 && c < 35 && r >= 20 && r < 27)) {
      ++removed;
      continue;
    }
    cloud.points.push_back(p);
    if ((r + c) % 3 == 0) {
      CloudPoint q = p;
      q.position += Eigen::Vector3d(0.3, -0.4, 0.05);
      cloud.points.push_back(q);
    }
  }
  ASSERT_EQ(removed, 12 * kCheckCells + 5 * 7);
  const long on_surface = static_cast<long>(cloud.points.size());
  for (int i = 0; i < 7; ++i) {
    CloudPoint p;
    p.position = {kX0 - 5 - i, kY0 + 3, kZ};  // west of and north of the raster
    cloud.points.push_back(p);
  }
  const SurfaceCheck s = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(4), Options());
  EXPECT_EQ(s.points, on_surface + 7);
  EXPECT_EQ(s.checked, on_surface);
  EXPECT_EQ(s.within, on_surface);
  ASSERT_GT(s.cells_seen, 0);
  EXPECT_EQ(s.cells_covered, s.cells_seen - removed);
  EXPECT_DOUBLE_EQ(s.coverage, static_cast<double>(s.cells_seen - removed) / s.cells_seen);
  EXPECT_EQ(s.cells_seen, kCheckCells * kCheckCells);
}

TEST(CheckAgainstSurface, CellsSeenByFewerThanMinImagesAreNotCounted) {
  SurfaceCheckOptions o = Options();
  o.min_images = 4;
  const SurfaceCheck three = CheckAgainstSurface(PointPerCell(), FlatSurface(), NadirBlock(3), o);
  EXPECT_EQ(three.cells_seen, 0);
  EXPECT_EQ(three.coverage, 0.0);
  // The accuracy part does not depend on the cameras.
  EXPECT_EQ(three.share_within, 1.0);
  const SurfaceCheck four = CheckAgainstSurface(PointPerCell(), FlatSurface(), NadirBlock(4), o);
  EXPECT_EQ(four.cells_seen, kCheckCells * kCheckCells);
}

TEST(CheckAgainstSurface, EmptySurfaceCellsAreNeitherCheckedNorSeen) {
  GeoRaster surface = FlatSurface();
  // Empty the west half (x < 1050): 100 raster columns, 25 check columns.
  for (int row = 0; row < kRasterCells; ++row) {
    for (int col = 0; col < kRasterCells / 2; ++col) {
      surface.at(col, row) = (row % 2 == 0) ? std::numeric_limits<float>::quiet_NaN() : -9999.0f;
    }
  }
  surface.nodata = -9999.0f;
  const SurfaceCheck s = CheckAgainstSurface(PointPerCell(), surface, NadirBlock(3), Options());
  EXPECT_EQ(s.points, kCheckCells * kCheckCells);
  EXPECT_EQ(s.checked, kCheckCells * kCheckCells / 2);
  EXPECT_EQ(s.cells_seen, kCheckCells * kCheckCells / 2);
  EXPECT_EQ(s.coverage, 1.0);
}

TEST(CheckAgainstSurface, EmptyCloudHasNoShareAndNoCoverage) {
  const SurfaceCheck s = CheckAgainstSurface(PointCloud{}, FlatSurface(), NadirBlock(3), Options());
  EXPECT_EQ(s.points, 0);
  EXPECT_EQ(s.checked, 0);
  EXPECT_EQ(s.share_within, 0.0);
  EXPECT_EQ(s.cells_seen, kCheckCells * kCheckCells);
  EXPECT_EQ(s.cells_covered, 0);
  EXPECT_EQ(s.coverage, 0.0);
}

TEST(CheckAgainstSurface, BadOptionsThrow) {
  const PointCloud cloud = PointPerCell();
  const GeoRaster surface = FlatSurface();
  const Block block = NadirBlock(3);
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    SurfaceCheckOptions o = Options();
    o.tolerance = bad;
    EXPECT_THROW(CheckAgainstSurface(cloud, surface, block, o), Error) << "tolerance " << bad;
    o = Options();
    o.cell_size = bad;
    EXPECT_THROW(CheckAgainstSurface(cloud, surface, block, o), Error) << "cell_size " << bad;
  }
}

// A step: the west half at kZ, the east half 4 higher. Points on both tops,
// on the wall between them, and off the surface by more or less than the
// radius, by the wall too.
TEST(ShareNearSurface, TopsAndWallsAreSurfaceAndTheRadiusIsThreeDimensional) {
  GeoRaster step = FlatSurface();
  for (int r = 0; r < kRasterCells; ++r) {
    for (int c = kRasterCells / 2; c < kRasterCells; ++c) step.at(c, r) = kZ + 4;
  }
  const double wall_x = kX0 + kRasterCells / 2 * kRasterCell;  // 1050
  const double y = 2050.25;
  PointCloud cloud;
  auto add = [&](double x, double z) {
    CloudPoint p;
    p.position = {x, y, z};
    cloud.points.push_back(p);
  };
  add(1020, kZ);              // west top
  add(1080, kZ + 4);          // east top
  add(wall_x, kZ + 2);        // on the wall
  add(wall_x - 0.1, kZ + 3);  // just west of the wall, on its face
  add(1020, kZ + 0.9);        // 0.9 above the west top
  add(1020, kZ + 1.1);        // 1.1 above it
  add(wall_x - 1.2, kZ + 3);  // 1.2 west of the wall, 3 above the west top
  add(1200, kZ);              // off the raster
  const double radius = 1.0;
  // Near: the two tops, the wall, its face, 0.9 above. Not: 1.1 above, the
  // point 1.2 from the wall and 3 above the ground, the one off the raster.
  EXPECT_DOUBLE_EQ(ShareNearSurface(cloud, step, radius), 5.0 / 8.0);
  EXPECT_DOUBLE_EQ(ShareNearSurface(cloud, step, 1.25), 7.0 / 8.0)
      << "1.1 above the top and 1.2 from the wall are within 1.25";
  EXPECT_DOUBLE_EQ(ShareNearSurface(PointCloud{}, step, radius), 0.0);
  EXPECT_THROW(ShareNearSurface(cloud, step, 0), Error);
}

}  // namespace
// Classes on the surface's grid: the north half ground (2), the south-west
// quarter water (9), the south-east quarter building (6).
GeoRaster QuarterClasses() {
  GeoRaster k = FlatSurface();
  for (int row = 0; row < kRasterCells; ++row) {
    for (int col = 0; col < kRasterCells; ++col) {
      k.at(col, row) = row < kRasterCells / 2 ? 2.0f : (col < kRasterCells / 2 ? 9.0f : 6.0f);
    }
  }
  return k;
}

TEST(CheckAgainstSurface, ClassesSplitTheCountsAndWaterIsNeverSeen) {
  // Every cell has a point on the surface except the building's, whose points
  // are two tolerances up.
  PointCloud cloud = PointPerCell();
  for (CloudPoint& p : cloud.points) {
    if (p.position.y() < kY0 - 50 && p.position.x() >= kX0 + 50) p.position.z() += 2 * kTolerance;
  }
  const GeoRaster classes = QuarterClasses();
  SurfaceCheckOptions o = Options();
  o.classes = &classes;
  const SurfaceCheck s = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), o);
  const long quarter = kCheckCells * kCheckCells / 4;
  ASSERT_EQ(s.by_class.size(), 3u);
  const ClassCheck& ground = s.by_class.at(2);
  const ClassCheck& water = s.by_class.at(9);
  const ClassCheck& roof = s.by_class.at(6);
  EXPECT_EQ(ground.checked, 2 * quarter);
  EXPECT_EQ(ground.within, 2 * quarter);
  EXPECT_EQ(ground.cells_seen, 2 * quarter);
  EXPECT_EQ(ground.cells_covered, 2 * quarter);
  EXPECT_EQ(roof.checked, quarter);
  EXPECT_EQ(roof.within, 0);
  EXPECT_EQ(roof.cells_seen, quarter);
  EXPECT_EQ(roof.cells_covered, 0);
  // Water's points count for accuracy; its cells are listed but not seen.
  EXPECT_EQ(water.checked, quarter);
  EXPECT_EQ(water.cells_seen, quarter);
  EXPECT_EQ(s.checked, 4 * quarter);
  EXPECT_EQ(s.within, 3 * quarter);
  EXPECT_EQ(s.cells_seen, 3 * quarter);
  EXPECT_EQ(s.cells_covered, 2 * quarter);
  EXPECT_NEAR(s.coverage, 2.0 / 3.0, 1e-12);

  // Without a class raster, water counts like any other ground.
  const SurfaceCheck plain = CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), Options());
  EXPECT_TRUE(plain.by_class.empty());
  EXPECT_EQ(plain.cells_seen, 4 * quarter);
  EXPECT_EQ(plain.cells_covered, 3 * quarter);
  // Nor when nothing is unmatchable.
  o.unmatchable_classes.clear();
  EXPECT_EQ(CheckAgainstSurface(cloud, FlatSurface(), NadirBlock(3), o).cells_seen, 4 * quarter);
}

TEST(CheckAgainstSurface, AClassRasterOffTheSurfaceGridThrows) {
  const GeoRaster good = QuarterClasses();
  GeoRaster shifted = good;
  shifted.origin_x += kRasterCell;
  GeoRaster coarser = good;
  coarser.cell_size *= 2;
  GeoRaster smaller = good;
  smaller.width -= 1;
  smaller.values.resize(static_cast<size_t>(smaller.width) * smaller.height);
  for (const GeoRaster* bad : {&shifted, &coarser, &smaller}) {
    SurfaceCheckOptions o = Options();
    o.classes = bad;
    EXPECT_THROW(CheckAgainstSurface(PointPerCell(), FlatSurface(), NadirBlock(3), o), Error);
  }
}

// Flat: every window lies on one plane, so only the raster's border matters.
// With a half-width of 1.5 the outermost ring of check cells (centres 1 from
// the edge) has no centred window inside the raster, but one shifted inwards.
TEST(WindowCoverageBound, OnAFlatSurfaceOnlyTheBorderRingNeedsAShift) {
  const WindowBound b = WindowCoverageBound(FlatSurface(), NadirBlock(3), Options(), 1.5);
  EXPECT_EQ(b.cells_seen, kCheckCells * kCheckCells);
  EXPECT_EQ(b.centred, (kCheckCells - 2) * (kCheckCells - 2));
  EXPECT_EQ(b.any, kCheckCells * kCheckCells);
}

// A 5-high box on 10 x 10 check cells: a window centred on the ring of
// cells either side of its edge (44 outside, 36 on top) straddles the step;
// one shifted away from the edge fits, where the ground beside the box is
// seen whole from 3 images.
TEST(WindowCoverageBound, WindowsStraddlingAStepDoNotFitButShiftedOnesDo) {
  GeoRaster box = FlatSurface();
  for (int r = 0; r < kRasterCells; ++r) {
    for (int c = 0; c < kRasterCells; ++c) {
      const double x = kX0 + (c + 0.5) * kRasterCell, y = kY0 - (r + 0.5) * kRasterCell;
      if (x > 1040 && x < 1060 && y > 2040 && y < 2060) {
        box.values[static_cast<size_t>(r) * kRasterCells + c] = static_cast<float>(kZ + 5);
      }
    }
  }
  const Block block = NadirBlock(3);
  const WindowBound flat = WindowCoverageBound(FlatSurface(), block, Options(), 1.5);
  const WindowBound b = WindowCoverageBound(box, block, Options(), 1.5);
  // The box hides little ground from cameras 100 above its middle, so almost
  // every cell stays seen (the check's own count).
  const SurfaceCheck s = CheckAgainstSurface(PointPerCell(), box, block, Options());
  EXPECT_EQ(b.cells_seen, s.cells_seen);
  EXPECT_GE(b.cells_seen, flat.cells_seen - 44);
  EXPECT_LE(b.centred, flat.centred - 80);
  EXPECT_GE(b.any - b.centred, 60);
  EXPECT_LE(b.any, b.cells_seen);
  EXPECT_THROW(WindowCoverageBound(box, block, Options(), 0.0), Error);
}

}  // namespace sapmvs

#include "sapmvs/run/cloud_dsm.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

PointCloud PlaneCloud(int nx, int ny, double spacing, double ox, double oy) {
  PointCloud c;
  c.crs = "EPSG:32632";
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      CloudPoint p;
      const double x = i * spacing, y = j * spacing;
      p.position = {ox + x, oy + y, 200.0 + 0.1 * x - 0.05 * y};
      c.points.push_back(p);
    }
  }
  return c;
}

TEST(CloudDsm, MeanSpacingOfAGridIsItsStep) {
  const PointCloud c = PlaneCloud(41, 37, 0.5, 500000.0, 5400000.0);
  // Nearest neighbour on the tilted plane: 0.5 m along y (slope 0.05).
  EXPECT_NEAR(MeanPointSpacing(c), 0.5 * std::sqrt(1 + 0.05 * 0.05), 1e-6);
  // Sampling every k-th point does not change it on a regular grid.
  EXPECT_NEAR(MeanPointSpacing(c, 100), 0.5 * std::sqrt(1 + 0.05 * 0.05), 1e-6);
  PointCloud one;
  one.points.resize(1);
  EXPECT_EQ(MeanPointSpacing(one), 0);
}

TEST(CloudDsm, FootprintAndDensityOfAGrid) {
  const PointCloud c = PlaneCloud(40, 20, 0.5, 1000.0, 2000.0);  // 20 m x 10 m
  const CloudFootprint f = MeasureFootprint(c, 1.0);
  EXPECT_EQ(f.occupied_cells, 20 * 10);
  EXPECT_DOUBLE_EQ(f.area, 200.0);
  EXPECT_DOUBLE_EQ(f.density, 800.0 / 200.0);
  EXPECT_THROW(MeasureFootprint(c, 0.0), Error);
}

TEST(CloudDsm, DsmOfAPlaneFollowsThePlaneAtCellCentres) {
  const PointCloud c = PlaneCloud(61, 43, 0.25, 500000.0, 5400000.0);
  DsmOptions o;
  double cell = 0;
  const GeoRaster r = RasterizeDsm(c, o, &cell);
  EXPECT_NEAR(cell, 2 * MeanPointSpacing(c), 1e-9);  // the default
  EXPECT_EQ(r.crs, "EPSG:32632");
  long valid = 0;
  for (int row = 0; row < r.height; ++row) {
    for (int col = 0; col < r.width; ++col) {
      if (std::isnan(r.at(col, row))) continue;
      ++valid;
      const Eigen::Vector2d xy = r.CellCenter(col, row);
      const double z = 200.0 + 0.1 * (xy.x() - 500000.0) - 0.05 * (xy.y() - 5400000.0);
      // The median of the cell's points: within the plane's rise over a cell.
      EXPECT_NEAR(r.at(col, row), z, 0.1 * cell + 1e-3) << col << " " << row;
    }
  }
  EXPECT_GT(valid, 0.9 * r.width * r.height);
  // The extent covers every point.
  EXPECT_LE(r.origin_x, 500000.0);
  EXPECT_GE(r.origin_y, 5400000.0 + 42 * 0.25);
  EXPECT_GE(r.origin_x + r.width * r.cell_size, 500000.0 + 60 * 0.25);
}

TEST(CloudDsm, SmallGapsAreFilledLargeHolesStayNodata) {
  PointCloud c = PlaneCloud(100, 100, 0.5, 0, 0);  // 50 m square
  std::vector<CloudPoint> kept;
  for (const CloudPoint& p : c.points) {
    const double x = p.position.x(), y = p.position.y();
    // Points on cell edges belong to the cell below them; removing x, y in
    // {10, 10.5, 11} empties exactly the cell around (10.5, 10.5).
    const bool small_gap = x >= 9.9 && x < 11.1 && y >= 9.9 && y < 11.1;
    const bool big_hole = x >= 25 && x < 40 && y >= 25 && y < 40;  // 15 m
    if (!small_gap && !big_hole) kept.push_back(p);
  }
  c.points = kept;
  DsmOptions o;
  o.cell_size = 1.0;
  const GeoRaster r = RasterizeDsm(c, o);
  auto at = [&](double x, double y) {
    return r.at(static_cast<int>((x - r.origin_x) / r.cell_size),
                static_cast<int>((r.origin_y - y) / r.cell_size));
  };
  EXPECT_FALSE(std::isnan(at(10.5, 10.5)));
  EXPECT_NEAR(at(10.5, 10.5), 200.0 + 0.1 * 10.5 - 0.05 * 10.5, 0.1);
  EXPECT_TRUE(std::isnan(at(32.5, 32.5)));
  o.fill_passes = 0;
  const GeoRaster unfilled = RasterizeDsm(c, o);
  EXPECT_TRUE(std::isnan(unfilled.at(static_cast<int>((10.5 - unfilled.origin_x)),
                                     static_cast<int>((unfilled.origin_y - 10.5)))));
}

TEST(CloudDsm, BadOptionsAndEmptyCloudsAreErrors) {
  PointCloud empty;
  EXPECT_THROW(RasterizeDsm(empty, DsmOptions{}), Error);
  const PointCloud c = PlaneCloud(5, 5, 1, 0, 0);
  DsmOptions o;
  o.cell_size = -1;
  EXPECT_THROW(RasterizeDsm(c, o), Error);
  o.cell_size = 1e-6;  // far too many cells
  EXPECT_THROW(RasterizeDsm(c, o), Error);
  o.cell_size = 1;
  o.fill_passes = 11;
  EXPECT_THROW(RasterizeDsm(c, o), Error);
}

}  // namespace
}  // namespace sapmvs

#include "sapmvs/block/dem.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sapmvs/io/raster_io.h"
#include "test_util.h"

namespace sapmvs {
namespace {

constexpr double kDemX0 = 500000, kDemY0 = 5400000, kDemCell = 0.5;

double DemPlane(double x, double y) { return 100 + 0.2 * (x - kDemX0) - 0.3 * (y - kDemY0); }

// A 41 x 31 raster of Plane at its cell centres, with one nodata cell and,
// for the coarse read, one 3 x 3 block of them.
GeoRaster DemPlaneRaster() {
  GeoRaster r;
  r.width = 41;
  r.height = 31;
  r.origin_x = kDemX0;
  r.origin_y = kDemY0;
  r.cell_size = kDemCell;
  r.nodata = -9999;
  r.crs = "EPSG:32632";
  r.values.resize(static_cast<size_t>(r.width) * r.height);
  for (int row = 0; row < r.height; ++row) {
    for (int col = 0; col < r.width; ++col) {
      const Eigen::Vector2d c = r.CellCenter(col, row);
      r.at(col, row) = static_cast<float>(DemPlane(c.x(), c.y()));
    }
  }
  r.at(4, 1) = r.nodata;
  for (int row = 6; row < 9; ++row)
    for (int col = 9; col < 12; ++col) r.at(col, row) = r.nodata;
  return r;
}

class DemTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    WriteGeoTiff(dir_ / "plane.tif", DemPlaneRaster());
  }
};

TEST_F(DemTest, ASmallRasterIsReadCellForCell) {
  const Dem dem = Dem::Load(dir_ / "plane.tif", 41 * 31);
  EXPECT_EQ(dem.width(), 41);
  EXPECT_EQ(dem.height(), 31);
  EXPECT_DOUBLE_EQ(dem.cell_size(), kDemCell);
  const GeoRaster r = DemPlaneRaster();
  const Eigen::Vector2d c = r.CellCenter(20, 15);
  EXPECT_NEAR(dem.Height(c.x(), c.y()), DemPlane(c.x(), c.y()), 1e-4);
  // Next to the nodata cell: no height.
  const Eigen::Vector2d n = r.CellCenter(4, 1);
  EXPECT_TRUE(std::isnan(dem.Height(n.x() + 0.1, n.y())));
}

// 1,271 cells in at most 200: 3 x 3 means of 13 x 10 cells of 1.5, the last
// 2 columns and the last row left out.
TEST_F(DemTest, AFineRasterIsReadAsTheMeanOfBlocksOfCells) {
  const Dem dem = Dem::Load(dir_ / "plane.tif", 200);
  EXPECT_EQ(dem.width(), 13);
  EXPECT_EQ(dem.height(), 10);
  EXPECT_DOUBLE_EQ(dem.cell_size(), 3 * kDemCell);
  // Coarse cell (col, row) covers fine columns 3 col .. 3 col + 2: its
  // centre is the fine cell 3 col + 1's, where the mean of a plane is.
  auto centre = [](int col, int row) {
    return Eigen::Vector2d(kDemX0 + (3 * col + 1.5) * kDemCell,
                           kDemY0 - (3 * row + 1.5) * kDemCell);
  };
  for (const auto& [col, row] : {std::pair{0, 0}, {12, 9}, {6, 4}, {2, 3}}) {
    const Eigen::Vector2d c = centre(col, row);
    EXPECT_NEAR(dem.Height(c.x(), c.y()), DemPlane(c.x(), c.y()), 1e-4) << col << " " << row;
  }
  // Coarse cell (1, 0) holds the nodata cell (4, 1): the mean of the other 8.
  double sum = 0;
  for (int row = 0; row < 3; ++row) {
    for (int col = 3; col < 6; ++col) {
      if (col == 4 && row == 1) continue;
      sum += DemPlane(kDemX0 + (col + 0.5) * kDemCell, kDemY0 - (row + 0.5) * kDemCell);
    }
  }
  // Between the centres of coarse cells (1, 0) and (2, 0), halfway: the mean
  // of the two (bilinear), the second of which is the plane's.
  const Eigen::Vector2d a = centre(1, 0), b = centre(2, 0);
  EXPECT_NEAR(dem.Height(0.5 * (a.x() + b.x()), a.y()), 0.5 * (sum / 8 + DemPlane(b.x(), b.y())),
              1e-4);
  // Coarse cell (3, 2) is all nodata: no height around it.
  const Eigen::Vector2d e = centre(3, 2);
  EXPECT_TRUE(std::isnan(dem.Height(e.x(), e.y())));
  // The surface is still found from above.
  const Eigen::Vector3d hit = dem.Intersect({kDemX0 + 10, kDemY0 - 7, 500}, {0, 0, -1});
  EXPECT_NEAR(hit.z(), DemPlane(kDemX0 + 10, kDemY0 - 7), 1e-3);
}

}  // namespace
}  // namespace sapmvs

// The simulator's true orthophoto (truth/ortho.tif, simulate/sim_ortho.h):
// each cell is what a camera looking straight down records of the cell top
// at its centre, on a grid georeferenced like truth/dsm.tif.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "ortho_truth_metrics.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/simulate/simulate.h"
#include "simulate/sim_ortho.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// The recorded colour of the cell top at local (x, y), as a noise-free
// image with gain 1 records it.
std::array<double, 3> RecordedTop(const sim::Scene& scene, double x, double y) {
  const Eigen::Vector3d shade = scene.Shade(scene.TopAt(x, y));
  return {sim::EncodeChannel(shade[0], 1), sim::EncodeChannel(shade[1], 1),
          sim::EncodeChannel(shade[2], 1)};
}

double TrueOrthoMedian(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(SimOrtho, CellsAreTheRecordedShadeOfTheTopAtTheirCentre) {
  sim::SceneSpec spec;
  spec.width = 60;
  spec.height = 45;
  spec.cell = 0.25;
  spec.building_min = 8;
  spec.building_max = 15;
  const sim::Scene scene = sim::Scene::Generate(spec, 7);
  // 0.7 m cells do not divide the scene: the last column and row reach past it.
  const double cell = 0.7;
  const sim::TrueOrtho point = sim::RenderTrueOrtho(scene, cell, 1);
  const GeoRaster& g = point.grid;
  ASSERT_EQ(g.width, static_cast<int>(std::ceil(scene.width() / cell)));
  ASSERT_EQ(g.height, static_cast<int>(std::ceil(scene.height() / cell)));
  EXPECT_EQ(g.origin_x, 0);
  EXPECT_EQ(g.origin_y, scene.height());
  EXPECT_EQ(g.cell_size, cell);
  // One point per cell is the recorded shade at the centre, exactly; the
  // row above (north) is not.
  long inside = 0, outside = 0, differ_north = 0;
  for (int row = 0; row < g.height; ++row) {
    for (int col = 0; col < g.width; ++col) {
      const Eigen::Vector2d p = g.CellCenter(col, row);
      const uint8_t* px = &point.rgba[(static_cast<size_t>(row) * g.width + col) * 4];
      if (p.x() >= scene.width() || p.y() < 0) {
        EXPECT_EQ(px[3], 0) << col << " " << row;
        ++outside;
        continue;
      }
      ASSERT_EQ(px[3], 255) << col << " " << row;
      ++inside;
      const std::array<double, 3> at = RecordedTop(scene, p.x(), p.y());
      for (int c = 0; c < 3; ++c) ASSERT_EQ(px[c], std::lround(at[c])) << col << " " << row;
      const std::array<double, 3> north = RecordedTop(scene, p.x(), p.y() + cell);
      differ_north += std::lround(north[1]) != px[1];
    }
  }
  EXPECT_GT(outside, 0);
  EXPECT_GT(differ_north, inside / 2);

  // 2 x 2 points per cell, as the images: their mean, close to the centre's
  // shade where the texture is smooth at the cell's scale.
  const sim::TrueOrtho ortho = sim::RenderTrueOrtho(scene, cell, 2);
  ASSERT_EQ(ortho.rgba.size(), point.rgba.size());
  std::vector<double> at_centre, one_cell_off;
  for (int row = 1; row < g.height - 1; ++row) {
    for (int col = 1; col < g.width - 1; ++col) {
      const size_t i = (static_cast<size_t>(row) * g.width + col) * 4;
      if (ortho.rgba[i + 3] == 0) continue;
      at_centre.push_back(std::abs(ortho.rgba[i + 1] - point.rgba[i + 1]));
      one_cell_off.push_back(std::abs(ortho.rgba[i + 1] - point.rgba[i + 4 + 1]));
    }
  }
  EXPECT_LE(TrueOrthoMedian(at_centre), 6.0);
  EXPECT_GT(TrueOrthoMedian(one_cell_off), TrueOrthoMedian(at_centre));
}

// The tiny block's truth/ortho.tif on truth/dsm.tif's extent, at the nominal
// GSD, coloured by the scene BuildWorld rebuilds.
TEST(SimOrtho, FileOfTheTinyBlock) {
  const fs::path dir = test::Simulated("tiny", 1);
  SimulateOptions o = test::SimulatedOptions("tiny", 1);
  o.out = dir;
  const SimulatedWorld world = BuildWorld(o);
  const ColorRaster ortho = ReadColorRaster(dir / "truth" / "ortho.tif");
  const GeoRaster dsm = ReadGeoRaster(dir / "truth" / "dsm.tif");
  const GeoRaster& g = ortho.grid;
  EXPECT_EQ(g.crs, dsm.crs);
  EXPECT_EQ(g.origin_x, dsm.origin_x);
  EXPECT_EQ(g.origin_y, dsm.origin_y);
  EXPECT_NEAR(g.cell_size, world.flight.gsd, 1e-9);
  const double w = dsm.width * dsm.cell_size, h = dsm.height * dsm.cell_size;
  EXPECT_GE(g.width * g.cell_size, w - 1e-6);
  EXPECT_LT(g.width * g.cell_size, w + g.cell_size);
  EXPECT_GE(g.height * g.cell_size, h - 1e-6);
  EXPECT_LT(g.height * g.cell_size, h + g.cell_size);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> col(0, g.width - 2), row(0, g.height - 2);
  std::vector<double> diff;
  for (int k = 0; k < 4000; ++k) {
    const int c = col(rng), r = row(rng);
    ASSERT_TRUE(ortho.Filled(c, r)) << c << " " << r;
    const Eigen::Vector2d p = g.CellCenter(c, r);
    const std::array<double, 3> at =
        RecordedTop(world.scene, p.x() - world.offset.x(), p.y() - world.offset.y());
    const uint8_t* px = &ortho.rgba[(static_cast<size_t>(r) * g.width + c) * 4];
    for (int i = 0; i < 3; ++i) diff.push_back(std::abs(px[i] - at[i]));
  }
  // 2 x 2 points per cell against one at the centre: close, not equal.
  EXPECT_LT(TrueOrthoMedian(diff), 3.0);
  EXPECT_NE(test::Slurp(dir / "truth" / "README.md").find("`truth/ortho.tif`"), std::string::npos);
}

}  // namespace
}  // namespace sapmvs

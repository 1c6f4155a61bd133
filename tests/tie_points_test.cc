#include "sapmvs/block/tie_points.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/raster_io.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// The tiny preset (shared by the test processes, read only).
fs::path TinyDir() { return test::Simulated("tiny", 3); }

class TiePointsTest : public ::testing::Test {
 protected:
  // The simulated block as a user without a surface prior brings it.
  static Block NoPrior(const fs::path& dir = TinyDir()) {
    Block b = ReadBlock(dir / "block.yaml");
    b.dem.clear();
    b.ground_height.reset();
    return b;
  }
};

double TruthAt(const GeoRaster& dsm, double x, double y) {
  const int c = static_cast<int>(std::floor((x - dsm.origin_x) / dsm.cell_size));
  const int r = static_cast<int>(std::floor((dsm.origin_y - y) / dsm.cell_size));
  if (c < 0 || r < 0 || c >= dsm.width || r >= dsm.height) return std::nan("");
  return dsm.at(c, r);
}

TEST_F(TiePointsTest, LieOnTheTrueSurface) {
  const Block block = NoPrior();
  const std::vector<TiePoint> points = TriangulateTiePoints(block);
  ASSERT_GE(points.size(), 30u);
  const GeoRaster dsm = ReadGeoRaster(TinyDir() / "truth" / "dsm.tif");
  const double gsd = EstimateBlockGeometry(ReadBlock(TinyDir() / "block.yaml")).gsd_median;
  std::vector<double> dz;
  for (const TiePoint& t : points) {
    EXPECT_GE(t.images.size(), 3u);
    const double z = TruthAt(dsm, t.position.x(), t.position.y());
    if (std::isfinite(z)) dz.push_back(std::abs(t.position.z() - z));
  }
  ASSERT_GE(dz.size(), points.size() * 9 / 10);
  std::sort(dz.begin(), dz.end());
  // Tie points are matched on images halved to at most max_side (tiny's 640
  // px once, to 320), so their precision is that level's pixel: measured
  // median 0.54 level GSD (1.08 full-resolution GSD), 75 points; at full
  // size it was 0.55 full-resolution GSD.
  int level = 0;
  const int side = std::max(block.images[0].camera.width(), block.images[0].camera.height());
  while ((side >> level) > TiePointOptions().max_side) ++level;
  const double level_gsd = std::ldexp(gsd, level);
  EXPECT_LT(dz[dz.size() / 2], level_gsd) << points.size() << " points";
  EXPECT_LT(dz[dz.size() * 8 / 10], 3 * level_gsd);
}

TEST_F(TiePointsTest, GiveTheFlyingHeightWithoutAPrior) {
  const BlockGeometry truth = EstimateBlockGeometry(ReadBlock(TinyDir() / "block.yaml"));
  ASSERT_EQ(truth.source, SurfaceSource::kDem);
  const BlockGeometry g = EstimateBlockGeometry(NoPrior());
  EXPECT_EQ(g.source, SurfaceSource::kTiePoints);
  EXPECT_EQ(ToString(g.source), "tie points");
  EXPECT_EQ(g.num_valid, 4);
  EXPECT_NEAR(g.flying_height, truth.flying_height, 0.05 * truth.flying_height);
  EXPECT_NEAR(g.gsd_median, truth.gsd_median, 0.05 * truth.gsd_median);
}

TEST_F(TiePointsTest, CameraOnlyBlocksHaveNone) {
  // Any block will do: the quickest simulated one (shared).
  Block b = NoPrior(test::Simulated("tiny", 1, 0.5));
  for (BlockImage& im : b.images) im.path.clear();
  EXPECT_TRUE(TriangulateTiePoints(b).empty());
  EXPECT_EQ(EstimateBlockGeometry(b).source, SurfaceSource::kNone);
}

TEST(TiePointOptions, NameTheFirstBadValue) {
  TiePointOptions o;
  EXPECT_EQ(o.Problem(), "");
  o.ratio = 1.5;
  EXPECT_EQ(o.Problem(), "ratio in (0, 1] (ratio = 1.5)");
  o = {};
  o.min_views = 1;
  EXPECT_EQ(o.Problem(), "min_views >= 2 (min_views = 1)");
}

}  // namespace
}  // namespace sapmvs

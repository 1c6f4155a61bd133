#include "sapmvs/block/block_geometry.h"

#include <gtest/gtest.h>

#include "sapmvs/block/block_reader.h"
#include "test_util.h"

namespace sapmvs {
namespace {

// Two strips of level cameras, 700 m above ground at Z = 300.
Block SyntheticAerialBlock() {
  Block b;
  const Intrinsics k = Intrinsics::FromFocalAndPixel(24, 5.7, 1000, 750);
  for (int strip = 0; strip < 2; ++strip) {
    for (int i = 0; i < 3; ++i) {
      BlockImage im;
      im.name = "s" + std::to_string(strip) + "_" + std::to_string(i);
      const double kappa = strip == 0 ? 0 : 180;
      const double x = 5e5 + (strip == 0 ? i : 2 - i) * 60.0;
      im.camera = Camera::FromAngles(k, {x, 5.4e6 + strip * 100.0, 1000}, 0, 0, kappa,
                                     AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
      b.images.push_back(im);
    }
  }
  return b;
}

TEST(BlockGeometry, GroundHeightGivesGsdAndExtent) {
  Block b = SyntheticAerialBlock();
  b.ground_height = 300;
  const BlockGeometry g = EstimateBlockGeometry(b);
  EXPECT_EQ(g.source, SurfaceSource::kGroundHeight);
  EXPECT_TRUE(g.aerial);
  EXPECT_EQ(g.num_valid, 6);
  const double gsd = 700 * 0.0057 / 24;  // H * pixel / focal
  EXPECT_NEAR(g.gsd_min, gsd, 1e-9);
  EXPECT_NEAR(g.gsd_max, gsd, 1e-9);
  EXPECT_NEAR(g.flying_height, 700, 1e-9);
  // Footprint: 1000 x 750 px of `gsd`; x spans 120 m of centres.
  EXPECT_NEAR(g.extent_max.x() - g.extent_min.x(), 120 + 1000 * gsd, 1e-6);
  EXPECT_NEAR(g.extent_max.y() - g.extent_min.y(), 100 + 750 * gsd, 1e-6);
}

TEST(BlockGeometry, SparsePointsTakePrecedenceOverGroundHeight) {
  Block b = SyntheticAerialBlock();
  b.ground_height = 0;  // wrong on purpose
  for (int i = 0; i < 50; ++i) b.sparse_points.emplace_back(5e5 + i * 3.0, 5.4e6 + 50, 350);
  const BlockGeometry g = EstimateBlockGeometry(b);
  EXPECT_EQ(g.source, SurfaceSource::kSparsePoints);
  EXPECT_NEAR(g.flying_height, 650, 1e-6);
}

TEST(BlockGeometry, ParallelNadirAxesGiveNoEstimate) {
  const BlockGeometry g = EstimateBlockGeometry(SyntheticAerialBlock());
  EXPECT_EQ(g.source, SurfaceSource::kNone);
  EXPECT_EQ(g.num_valid, 0);
}

TEST(BlockGeometry, NgiDemGivesTheExpectedGsd) {
  SAPMVS_REQUIRE_PATH(test::SharedDir() / "datasets/orthority_ngi_odm/ngi/dem.tif");
  const BlockGeometry g = EstimateBlockGeometry(ReadBlock(test::TestDir() / "blocks" / "ngi.yaml"));
  EXPECT_EQ(g.source, SurfaceSource::kDem);
  EXPECT_EQ(g.num_valid, 4);
  // 120 mm lens, 144 um pixels (12x 12 um), about 4.8 to 5.1 km above the
  // DEM: 5.6 to 6.2 m.
  EXPECT_GT(g.gsd_min, 5.5);
  EXPECT_LT(g.gsd_max, 6.2);
  for (size_t i = 0; i < g.images.size(); ++i) {
    // H / f with H measured along the optical axis to the DEM intersection.
    EXPECT_NEAR(g.images[i].gsd, g.images[i].depth / 833.3333, 0.02);
  }
}

TEST(BlockGeometry, HerzJesuTiePointsFindTheFacade) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const BlockGeometry g = EstimateBlockGeometry(ReadBlock(test::HerzJesu()));
  EXPECT_EQ(g.source, SurfaceSource::kTiePoints);
  EXPECT_FALSE(g.aerial);
  EXPECT_EQ(g.num_valid, 8);
  // The facade stands 10 to 30 m from the cameras.
  for (const ImageGeometry& ig : g.images) {
    EXPECT_GT(ig.depth, 10);
    EXPECT_LT(ig.depth, 30);
  }
}

}  // namespace
}  // namespace sapmvs

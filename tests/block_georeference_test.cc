#include "block/block_georeference.h"

#include <gtest/gtest.h>

#include <string>

#include "sapmvs/block/rotation.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Three nadir-looking cameras and a field of sparse points in the ENU frame
// about a reference point, as COLMAP's model_aligner leaves a UAV flight.
Block EnuBlock() {
  Block block;
  block.source = "enu_block";
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 374.5, 1000, 750);
  for (int i = 0; i < 3; ++i) {
    BlockImage im;
    im.name = "img" + std::to_string(i);
    im.camera = Camera::FromAngles(k, Eigen::Vector3d(60.0 * i - 60, 20, 150), 2, -3, 10 * i,
                                   AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
    block.images.push_back(im);
  }
  for (int x = -100; x <= 100; x += 10)
    for (int y = -40; y <= 80; y += 10) block.sparse_points.emplace_back(x, y, 0.1 * x);
  return block;
}

// The same block in ECEF (EPSG:4978), moved rigidly by the ENU frame's own
// axes and origin.
Block AsEcef(Block block, const GeoReference& ref) {
  const TopocentricToUtm map(ref);
  const Eigen::Matrix3d& r = map.enu_to_ecef();
  for (BlockImage& im : block.images) {
    const Camera& c = im.camera;
    im.camera =
        Camera(c.intrinsics(), c.rotation() * r.transpose(), map.origin_ecef() + r * c.center());
  }
  for (Eigen::Vector3d& p : block.sparse_points) p = map.origin_ecef() + r * p;
  return block;
}

BlockReadOptions WithOrigin(const GeoReference& ref) {
  BlockReadOptions o;
  o.enu_origin = Eigen::Vector3d(ref.latitude, ref.longitude, ref.altitude);
  return o;
}

TEST(GeodeticOf, InvertsTheEllipsoidFormula) {
  for (const GeoReference& g : {GeoReference{47.0, 9.0, 400}, GeoReference{-33.9, -122.3, 50},
                                GeoReference{0.0, 179.5, 9000}, GeoReference{83.5, -10, -20}}) {
    const GeoReference back = GeodeticOf(TopocentricToUtm(g).origin_ecef());
    EXPECT_NEAR(back.latitude, g.latitude, 1e-9);
    EXPECT_NEAR(back.longitude, g.longitude, 1e-9);
    EXPECT_NEAR(back.altitude, g.altitude, 1e-4);
  }
}

// The point 100 m above the ENU origin against PROJ's own UTM coordinates
// of the origin (`gdaltransform -s_srs EPSG:4979 -t_srs EPSG:326zz/327zz`,
// PROJ 9.1): on the central meridian and 2.9 degrees east of it (k =
// 1.0006), north and south of the equator.
TEST(ApplyFrame, EnuOriginLandsWhereProjPutsIt) {
  struct Case {
    GeoReference ref;
    const char* crs;
    double easting, northing;
  };
  for (const Case& c :
       {Case{{47.0, 9.0, 400}, "EPSG:32632", 500000.0, 5205164.1101522},
        Case{{47.0, 11.9, 400}, "EPSG:32632", 720467.702792203, 5209246.3428523},
        Case{{-33.9, -122.3, 50}, "EPSG:32710", 564719.747319336, 6248711.22251887},
        Case{{-33.9, -120.1, 50}, "EPSG:32710", 768165.726830202, 6245144.63162635}}) {
    Block block = EnuBlock();
    block.images[1].camera =
        Camera::FromAngles(block.images[1].camera.intrinsics(), Eigen::Vector3d(0, 0, 100), 0, 0, 0,
                           AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
    ApplyFrame(WithOrigin(c.ref), &block);
    EXPECT_EQ(block.crs, c.crs);
    const Eigen::Vector3d p = block.images[1].camera.center();
    EXPECT_NEAR(p.x(), c.easting, 1e-3) << c.crs;
    EXPECT_NEAR(p.y(), c.northing, 1e-3) << c.crs;
    EXPECT_NEAR(p.z(), c.ref.altitude + 100, 1e-3);
    EXPECT_NE(block.frame_note.find("from ENU"), std::string::npos) << block.frame_note;
  }
}

// A block in ECEF is found and lands where the same block in ENU with its
// origin given lands: the same UTM zone, centres and points within a
// millimetre, the same pictures of the points.
TEST(ApplyFrame, EcefIsFoundAndMatchesTheEnuBlock) {
  for (const GeoReference& ref : {GeoReference{47.0, 11.9, 400}, GeoReference{-33.9, -122.3, 50}}) {
    Block enu = EnuBlock();
    Block ecef = AsEcef(enu, ref);
    EXPECT_FALSE(LooksEcef(enu));
    EXPECT_TRUE(LooksEcef(ecef));
    ApplyFrame(WithOrigin(ref), &enu);
    ApplyFrame(BlockReadOptions{}, &ecef);
    EXPECT_EQ(ecef.crs, enu.crs);
    EXPECT_NE(ecef.frame_note.find("ECEF"), std::string::npos) << ecef.frame_note;
    for (size_t i = 0; i < enu.images.size(); ++i) {
      EXPECT_LT((ecef.images[i].camera.center() - enu.images[i].camera.center()).norm(), 1e-3);
    }
    double worst = 0;
    for (size_t p = 0; p < enu.sparse_points.size(); ++p) {
      EXPECT_LT((ecef.sparse_points[p] - enu.sparse_points[p]).norm(), 1e-3);
      for (size_t i = 0; i < enu.images.size(); ++i) {
        const Camera &a = enu.images[i].camera, &b = ecef.images[i].camera;
        if (a.Depth(enu.sparse_points[p]) <= 0) continue;
        worst = std::max(
            worst, (a.Project(enu.sparse_points[p]) - b.Project(ecef.sparse_points[p])).norm());
      }
    }
    EXPECT_LT(worst, 0.01) << "pixels";
  }
}

// A projected block far north (northing 6.36e6 m, its centres at the Earth's
// radius from the origin) is not ECEF: it looks along its own -Z.
TEST(ApplyFrame, AFarNorthUtmBlockIsNotEcef) {
  Block block = EnuBlock();
  for (BlockImage& im : block.images) {
    const Camera& c = im.camera;
    im.camera =
        Camera(c.intrinsics(), c.rotation(), c.center() + Eigen::Vector3d(500000, 6.36e6, 0));
  }
  EXPECT_GT(block.images[0].camera.center().norm(), 6.3558e6);
  EXPECT_FALSE(LooksEcef(block));
  ApplyFrame(BlockReadOptions{}, &block);
  EXPECT_EQ(block.crs, "");
  EXPECT_NE(block.frame_note.find("local frame"), std::string::npos) << block.frame_note;
}

TEST(ApplyFrame, CrsNamesTheFrameAndContradictionsAreRefused) {
  Block block = EnuBlock();
  BlockReadOptions o;
  o.crs = "EPSG:32632";
  ApplyFrame(o, &block);
  EXPECT_EQ(block.crs, "EPSG:32632");
  EXPECT_EQ(block.images[0].camera.center(), EnuBlock().images[0].camera.center());

  Block other = EnuBlock();
  other.crs = "EPSG:2056";
  EXPECT_THROW(ApplyFrame(o, &other), Error);
  EXPECT_THROW(ApplyFrame(WithOrigin({47, 9, 400}), &other), Error);
  o.enu_origin = Eigen::Vector3d(47, 9, 400);
  Block both = EnuBlock();
  EXPECT_THROW(ApplyFrame(o, &both), Error);
}

}  // namespace
}  // namespace sapmvs

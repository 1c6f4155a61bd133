#include "block/topocentric_to_utm.h"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <memory>

#include "sapmvs/block/rotation.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(TopocentricToUtm, ZoneFromLongitude) {
  EXPECT_EQ(UtmEpsgFor({24.68, 120.95, 0}), 32651);
  EXPECT_EQ(UtmEpsgFor({-33.9, 18.4, 0}), 32734);
  EXPECT_EQ(UtmEpsgFor({0, -180, 0}), 32601);
  EXPECT_EQ(UtmEpsgFor({0, 180, 0}), 32660);   // the antimeridian closes zone 60
  EXPECT_EQ(UtmEpsgFor({47, 6.0, 0}), 32632);  // a zone's western edge
}

TEST(TopocentricToUtm, ReferenceBoundaries) {
  EXPECT_EQ(GeoReference({84, 0, 0}).Problem(), "");
  EXPECT_EQ(GeoReference({-80, 0, 0}).Problem(), "");
  EXPECT_EQ(GeoReference({0, -180, 0}).Problem(), "");
  EXPECT_NE(GeoReference({84.01, 0, 0}).Problem().find("UTM zones"), std::string::npos);
  EXPECT_NE(GeoReference({-80.01, 0, 0}).Problem().find("UTM zones"), std::string::npos);
  EXPECT_NE(GeoReference({90.5, 0, 0}).Problem().find("[-90, 90]"), std::string::npos);
  EXPECT_NE(GeoReference({0, 180.5, 0}).Problem().find("longitude"), std::string::npos);
  EXPECT_NE(GeoReference({0, 0, NAN}).Problem().find("finite"), std::string::npos);
  EXPECT_THROW(TopocentricToUtm({91, 0, 0}), Error);
}

// The reference point itself, through OGR from geographic 3D coordinates
// (not through ECEF as the class goes), lands where the class puts ENU 0.
TEST(TopocentricToUtm, OriginIsTheReferencePoint) {
  const GeoReference ref{24.680944366323203, 120.9505624780138, 57.5};
  OGRSpatialReference geo, utm;
  geo.importFromEPSG(4979);
  utm.importFromEPSG(32651);
  geo.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  utm.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&geo, &utm));
  double x = ref.longitude, y = ref.latitude, z = ref.altitude;
  ASSERT_TRUE(t->Transform(1, &x, &y, &z));
  const TopocentricToUtm map(ref);
  const Eigen::Vector3d o = map.Transform(Eigen::Vector3d::Zero());
  EXPECT_NEAR(o.x(), x, 1e-6);
  EXPECT_NEAR(o.y(), y, 1e-6);
  EXPECT_NEAR(o.z(), ref.altitude, 1e-6);
  // 100 m up stays 100 m up (ENU's up is the ellipsoid normal there).
  EXPECT_NEAR(map.Transform(Eigen::Vector3d(0, 0, 100)).z(), ref.altitude + 100, 1e-6);
}

// Grid north turns from true north by about dlambda * sin(phi) (first order);
// the local rotation is a turn about the vertical, and the horizontal scale
// is the projection's k, 0.9996 at the central meridian.
TEST(TopocentricToUtm, LocalRotationIsTheConvergence) {
  for (const GeoReference ref :
       {GeoReference{24.68, 120.95, 0}, GeoReference{-33.9, 18.4, 100}, GeoReference{60, 9.0, 0}}) {
    const TopocentricToUtm map(ref);
    double scale = 0;
    const Eigen::Matrix3d r = map.LocalRotation(Eigen::Vector3d::Zero(), &scale);
    const double central = (map.epsg() % 100) * 6 - 183;
    const double expect = (ref.longitude - central) * std::sin(ref.latitude * kPi / 180);
    const Eigen::Vector3d north = r * Eigen::Vector3d::UnitY();  // ENU north on the grid
    const double turn = std::atan2(-north.x(), north.y()) * 180 / kPi;
    EXPECT_NEAR(turn, expect, 0.01) << ref.latitude << " " << ref.longitude;
    EXPECT_NEAR(r(2, 2), 1, 1e-9);
    if (ref.longitude == 9.0) {
      EXPECT_NEAR(scale, 0.9996, 1e-6);
    }
  }
}

// A block moved by MoveTopocentricToUtm: every point and centre moved
// exactly, and its sparse points reproject within a fraction of a pixel. At
// 8 E, 76 km west of zone 32's central meridian, UTM scales horizontal
// distances by k = 0.99967 and heights by 1, which no camera rotation can
// follow: (1 - k) x 1000 px x the rays' slope bounds the change (measured
// 0.26 px at the image corners).
TEST(TopocentricToUtm, MovesABlockAndMeasuresTheChange) {
  const GeoReference ref{47.0, 8.0, 400};
  Block block;
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 374.5, 1000, 750);
  for (int i = 0; i < 3; ++i) {
    BlockImage im;
    im.name = "img" + std::to_string(i);
    im.camera = Camera::FromAngles(k, Eigen::Vector3d(60.0 * i, 20, 150), 2, -3, 10 * i,
                                   AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
    block.images.push_back(im);
  }
  for (int x = -40; x <= 160; x += 10)
    for (int y = -40; y <= 80; y += 10) block.sparse_points.emplace_back(x, y, 0.1 * x);
  const std::vector<Eigen::Vector3d> enu_points = block.sparse_points;
  const TopocentricToUtmReport report = MoveTopocentricToUtm(ref, &block);
  EXPECT_EQ(block.crs, "EPSG:32632");
  EXPECT_EQ(report.epsg, 32632);
  EXPECT_EQ(report.points_checked, static_cast<int>(enu_points.size()));
  EXPECT_GE(report.max_reprojection_change_px, 0);
  EXPECT_LT(report.max_reprojection_change_px, 0.5);
  const TopocentricToUtm map(ref);
  for (size_t i = 0; i < enu_points.size(); ++i)
    EXPECT_LT((block.sparse_points[i] - map.Transform(enu_points[i])).norm(), 1e-9);
  EXPECT_LT((block.images[1].camera.center() - map.Transform(Eigen::Vector3d(60, 20, 150))).norm(),
            1e-9);
}

}  // namespace
}  // namespace sapmvs

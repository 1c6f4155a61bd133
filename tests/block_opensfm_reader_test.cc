#include <gtest/gtest.h>

#include <ogr_spatialref.h>

#include <Eigen/Geometry>

#include <fstream>
#include <memory>

#include "sapmvs/block_reader.h"
#include "sapmvs/error.h"
#include "sapmvs/image_io.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

fs::path OdmJson() {
  return test::SharedDir() / "datasets/orthority_ngi_odm/odm/opensfm/reconstruction.json";
}

// UTM 51N (the DSM's frame) to OpenSfM's topocentric ENU about `lla`, through
// ECEF with GDAL/PROJ: a test-only conversion, independent of the reader.
std::vector<Eigen::Vector3d> UtmToEnu(const std::vector<Eigen::Vector3d>& pts, double lat,
                                      double lon, double alt) {
  OGRSpatialReference utm, geo, ecef;
  utm.importFromEPSG(32651);
  geo.importFromEPSG(4979);
  ecef.importFromEPSG(4978);
  for (OGRSpatialReference* s : {&utm, &geo, &ecef})
    s->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_ecef(
      OGRCreateCoordinateTransformation(&utm, &ecef));
  std::unique_ptr<OGRCoordinateTransformation> ref_to_ecef(
      OGRCreateCoordinateTransformation(&geo, &ecef));
  double rx = lon, ry = lat, rz = alt;
  ref_to_ecef->Transform(1, &rx, &ry, &rz);
  const double p = lat * M_PI / 180, l = lon * M_PI / 180;
  Eigen::Matrix3d r;
  r << -std::sin(l), std::cos(l), 0,                                        //
      -std::sin(p) * std::cos(l), -std::sin(p) * std::sin(l), std::cos(p),  //
      std::cos(p) * std::cos(l), std::cos(p) * std::sin(l), std::sin(p);
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& q : pts) {
    // The DSM's heights are the same heights as the cameras' Z (ellipsoidal
    // here, since reference_lla has altitude 0 and the cameras agree).
    double x = q.x(), y = q.y(), z = q.z();
    to_ecef->Transform(1, &x, &y, &z);
    out.push_back(r * (Eigen::Vector3d(x, y, z) - Eigen::Vector3d(rx, ry, rz)));
  }
  return out;
}

TEST(OpenSfmReader, ReadsTheOdmReconstruction) {
  SAPMVS_REQUIRE_PATH(OdmJson());
  const Block block = ReadBlock(OdmJson().parent_path().parent_path());  // the ODM project folder
  EXPECT_EQ(block.format, "opensfm");
  ASSERT_EQ(block.images.size(), 4u);
  for (const BlockImage& im : block.images) {
    const Intrinsics& k = im.camera.intrinsics();
    EXPECT_EQ(k.width, 1368);
    EXPECT_EQ(k.height, 912);
    EXPECT_NEAR(k.fx, 911.719212, 1e-5);
    EXPECT_NEAR(k.cx, 681.385011, 1e-5);
    EXPECT_NEAR(k.cy, 462.000565, 1e-5);
    EXPECT_DOUBLE_EQ(k.distortion.k1, -0.2640629100413887);
    EXPECT_DOUBLE_EQ(k.distortion.k3, -0.02581956399353581);
    EXPECT_DOUBLE_EQ(k.distortion.p2, 0.0002595206713083041);
  }
  EXPECT_NE(block.frame_note.find("lat 24.68094437"), std::string::npos) << block.frame_note;
}

TEST(OpenSfmReader, RelativeOrientationMatchesTheUtmConversion) {
  SAPMVS_REQUIRE_PATH(OdmJson());
  // ENU and UTM differ by a rotation about the vertical (grid convergence)
  // and a scale near 1: relative rotations and distances must agree.
  const Block enu = ReadBlock(OdmJson());
  const Block utm = ReadBlock(test::TestDir() / "blocks" / "odm.yaml");
  for (size_t i = 0; i < enu.images.size(); ++i) {
    const int ui = utm.FindImage(enu.images[i].name);
    ASSERT_GE(ui, 0);
    for (size_t j = i + 1; j < enu.images.size(); ++j) {
      const int uj = utm.FindImage(enu.images[j].name);
      const Eigen::Matrix3d a =
          enu.images[i].camera.rotation() * enu.images[j].camera.rotation().transpose();
      const Eigen::Matrix3d b =
          utm.images[ui].camera.rotation() * utm.images[uj].camera.rotation().transpose();
      const double angle = Eigen::AngleAxisd(a * b.transpose()).angle() * 180 / M_PI;
      EXPECT_LT(angle, 0.05) << "degrees";
      const double da = (enu.images[i].camera.center() - enu.images[j].camera.center()).norm();
      const double db = (utm.images[ui].camera.center() - utm.images[uj].camera.center()).norm();
      EXPECT_NEAR(da / db, 1.0, 2e-3);
    }
  }
}

TEST(OpenSfmReader, UndistortedImagesArePhotoConsistentWithTheDsmInEnu) {
  SAPMVS_REQUIRE_PATH(test::SharedDir() / "datasets/orthority_ngi_odm/derived/odm/dsm_points.xyz");
  const Block block = ReadBlock(OdmJson());
  const auto utm =
      test::ReadXyz(test::SharedDir() / "datasets/orthority_ngi_odm/derived/odm/dsm_points.xyz", 3);
  const auto points = UtmToEnu(utm, 24.680944366323203, 120.9505624780138, 0.0);
  std::vector<LoadedImage> images;
  std::vector<std::string> names;
  for (const BlockImage& im : block.images) {
    images.push_back(LoadUndistorted(im));
    names.push_back(im.name);
  }
  const test::BlockNcc ncc = test::MeasureBlockNcc(images, names, points);
  ASSERT_GE(ncc.pairs, 4);
  // The data's README: the ENU route is as consistent as UTM, up to a common
  // offset of a few metres (5 to 20 px).
  // Measured: 0.34 to 0.70 per pair, mean 0.46.
  EXPECT_GE(ncc.mean, 0.35);
  EXPECT_GE(ncc.worst_margin, 0.2);
}

using Malformed = test::MalformedText;

class OpenSfmReaderMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(OpenSfmReaderMalformed, FailsNamingFileAndLine) {
  const fs::path dir = test::ScratchDir();
  std::ofstream(dir / "reconstruction.json") << GetParam().text;
  test::ExpectInputError([&] { ReadBlock(dir / "reconstruction.json"); }, "reconstruction.json",
                         GetParam().line, GetParam().expect);
}

const char kCamera[] =
    "[{\n \"cameras\": {\n  \"c\": {\"projection_type\": \"perspective\", \"width\": 640,\n"
    "   \"height\": 480, \"focal\": 0.9, \"k1\": 0, \"k2\": 0}\n },\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, OpenSfmReaderMalformed,
    ::testing::Values(
        Malformed{"InvalidJson", "[{\n \"cameras\": {\n  \"c\": [1, 2,\n }\n", 4, "not valid JSON"},
        Malformed{"MissingRotation",
                  std::string(kCamera) + " \"shots\": {\n  \"img1\": {\"camera\": \"c\", "
                                         "\"translation\": [0, 0, 0]}\n }\n}]\n",
                  7, "shots/img1/rotation: expected an array of 3 numbers"},
        Malformed{"UnknownProjection",
                  "[{\n \"cameras\": {\n  \"fish\": {\"projection_type\": \"fisheye62\", "
                  "\"width\": 640, \"height\": 480}\n },\n \"shots\": {}\n}]\n",
                  3, "unsupported projection type 'fisheye62'"},
        Malformed{"UnknownCamera",
                  std::string(kCamera) +
                      " \"shots\": {\n  \"img1\": {\"camera\": \"other\", "
                      "\"rotation\": [0, 0, 0], \"translation\": [0, 0, 0]}\n }\n}]\n",
                  7, "unknown camera 'other'"},
        Malformed{"NotAnArray", "{\"cameras\": {}}\n", 1, "expected an array of reconstructions"}),
    [](const auto& p) { return p.param.name; });

}  // namespace
}  // namespace sapmvs

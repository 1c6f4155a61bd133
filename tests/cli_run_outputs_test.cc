// What `sapmvs run` writes, read back by the tools users open it with:
// cloud.las by @loaders.gl/las and copc.js (node, from npm) and by our own
// reader, in both LAS versions; the DSM's pictures and the orthophoto by GDAL
// and OpenCV. One run
// per LAS version for the whole suite (test::SharedRun; the LAS 1.2 one is
// also CliRunTest's).
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test_util.h"
#include "ortho_truth_metrics.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/cloud_las.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

class CliRunOutputsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SAPMVS_REQUIRE_OPENCL_DEVICE();
    const fs::path block = test::Simulated("tiny", 1) / "block.yaml";
    for (const std::string version : {"1.2", "1.4"}) {
      const auto [out, r] =
          test::SharedRun(block, version == "1.2" ? "-q" : "-q --las-version " + version);
      ASSERT_EQ(r.exit_code, 0) << "sapmvs run (LAS " << version << ") failed: " << r.err;
      out_[version] = out;
    }
  }

  // The run's folder (read only) for LAS `version`.
  fs::path Out(const std::string& version) const { return out_.at(version); }

 private:
  std::map<std::string, fs::path> out_;
};

// Where scripts/install-deps.sh puts the npm readers; "" when absent.
std::string NpmDirWithLasReaders() {
  std::stringstream dirs(SAPMVS_NPM_DIRS);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const fs::path m = fs::path(dir) / "node_modules";
    if (fs::exists(m / "copc" / "package.json") &&
        fs::exists(m / "@loaders.gl" / "las" / "package.json") &&
        fs::exists(m / "@loaders.gl" / "core" / "package.json")) {
      return dir;
    }
  }
  return "";
}

// tests/las_check.cjs's JSON for `las`, every `stride`-th point.
nlohmann::json ReadWithNode(const std::string& npm, const fs::path& las, int stride) {
  const fs::path json = test::ScratchDir() / (las.stem().string() + "_node.json");
  const std::string cmd = "node " + (fs::path(SAPMVS_TEST_DIR) / "las_check.cjs").string() + " " +
                          npm + " " + las.string() + " " + std::to_string(stride) + " > " +
                          json.string();
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("failed: " + cmd);
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

// The Extra Bytes values cloud.ply says point `q` has, in cloud.las's order.
std::vector<double> ExpectedExtras(const CloudPoint& q) {
  return {q.score, double(q.num_views), q.normal.x(), q.normal.y(), q.normal.z()};
}

const std::vector<std::string> kExtraNames = {kLasScoreField, kLasViewsField, kLasNormalFields[0],
                                              kLasNormalFields[1], kLasNormalFields[2]};

// copc.js's reading of `las` against cloud.ply: count, coordinates to the
// millimetre (the LAS scale), Extra Bytes names and values exactly (float32
// and uint16 hold the PLY's float and count).
void ExpectCopcMatchesPly(const nlohmann::json& copc, const PointCloud& cloud,
                          const std::string& version, int format) {
  ASSERT_FALSE(copc.contains("error")) << copc;
  EXPECT_EQ(copc.at("version"), version);
  EXPECT_EQ(copc.at("format"), format);
  ASSERT_EQ(copc.at("count").get<size_t>(), cloud.points.size());
  std::vector<std::string> fields = {"X", "Y", "Z"};
  fields.insert(fields.end(), kExtraNames.begin(), kExtraNames.end());
  ASSERT_EQ(copc.at("fields").get<std::vector<std::string>>(), fields);
  const auto& eb = copc.at("extra_bytes");
  EXPECT_EQ(eb[0].at("type"), "float");
  EXPECT_EQ(eb[1].at("type"), "unsigned");
  EXPECT_EQ(eb[1].at("length"), 2);
  ASSERT_GT(copc.at("points").size(), 100u);
  for (const auto& p : copc.at("points")) {
    const CloudPoint& q = cloud.points[p[0].get<size_t>()];
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(p[1 + a].get<double>(), q.position[a], 0.0005 + 1e-9);
    const std::vector<double> extras = ExpectedExtras(q);
    for (size_t k = 0; k < extras.size(); ++k) {
      ASSERT_EQ(p[4 + k].get<double>(), extras[k]) << kExtraNames[k] << " of " << p;
    }
  }
}

TEST_F(CliRunOutputsTest, LasIsReadByLoadersGlAndCopcWithScoreViewsAndNormals) {
  const std::string npm = NpmDirWithLasReaders();
  if (npm.empty() || std::system("node --version >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "node, copc.js or @loaders.gl/las missing (scripts/install-deps.sh installs "
                    "them into build/npm when the npm registry is reachable)";
  }
  const PointCloud cloud = ReadPly(Out("1.2") / "cloud.ply");
  ASSERT_TRUE(cloud.has_scores && cloud.has_views && cloud.has_normals);
  const nlohmann::json j = ReadWithNode(npm, Out("1.2") / "cloud.las", 7);

  const nlohmann::json& gl = j.at("loaders_gl");
  ASSERT_FALSE(gl.contains("error")) << gl;
  EXPECT_EQ(gl.at("format"), 2);
  ASSERT_EQ(gl.at("count").get<size_t>(), cloud.points.size());
  ASSERT_GT(gl.at("points").size(), 100u);
  for (const auto& p : gl.at("points")) {
    const CloudPoint& q = cloud.points[p[0].get<size_t>()];
    for (int a = 0; a < 3; ++a) ASSERT_NEAR(p[1 + a].get<double>(), q.position[a], 0.0005 + 1e-9);
  }
  ExpectCopcMatchesPly(j.at("copc"), cloud, "1.2", 2);
}

TEST_F(CliRunOutputsTest, Las14IsReadByCopcWithTheSameExtraBytes) {
  const std::string npm = NpmDirWithLasReaders();
  if (npm.empty() || std::system("node --version >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "node, copc.js or @loaders.gl/las missing (scripts/install-deps.sh installs "
                    "them into build/npm when the npm registry is reachable)";
  }
  const PointCloud cloud = ReadPly(Out("1.4") / "cloud.ply");
  ExpectCopcMatchesPly(ReadWithNode(npm, Out("1.4") / "cloud.las", 7).at("copc"), cloud, "1.4", 7);
}

TEST_F(CliRunOutputsTest, OurReaderReadsBothVersionsWithTheirExtraBytes) {
  for (const std::string version : {"1.2", "1.4"}) {
    SCOPED_TRACE("LAS " + version);
    const PointCloud cloud = ReadPly(Out(version) / "cloud.ply");
    const LasCloud las = ReadLas(Out(version) / "cloud.las", true);
    EXPECT_EQ(std::to_string(las.version_major) + "." + std::to_string(las.version_minor), version);
    EXPECT_EQ(las.point_format, version == "1.2" ? 2 : 7);
    EXPECT_FALSE(las.crs_wkt.empty());
    ASSERT_EQ(las.points.size(), cloud.points.size());
    ASSERT_EQ(las.extras.size(), kExtraNames.size());
    for (size_t k = 0; k < kExtraNames.size(); ++k) EXPECT_EQ(las.extras[k].name, kExtraNames[k]);
    for (size_t i = 0; i < cloud.points.size(); ++i) {
      const CloudPoint& q = cloud.points[i];
      ASSERT_NEAR(las.points[i].z, q.position.z(), 0.0005 + 1e-9) << i;
      EXPECT_EQ(ColorTo8(las.points[i].r), q.color[0]) << i;
      const std::vector<double> extras = ExpectedExtras(q);
      for (size_t k = 0; k < extras.size(); ++k) {
        ASSERT_EQ(las.extras[k].values[i], extras[k]) << kExtraNames[k] << " of point " << i;
      }
    }
  }
}

TEST_F(CliRunOutputsTest, DsmPicturesShareTheDsmsGeoreference) {
  const fs::path out = Out("1.2");
  GDALAllRegister();
  std::unique_ptr<GDALDataset> dsm(GDALDataset::Open((out / "dsm.tif").c_str(), GDAL_OF_RASTER));
  std::unique_ptr<GDALDataset> color(
      GDALDataset::Open((out / "dsm_color.tif").c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(dsm && color);
  EXPECT_EQ(color->GetRasterCount(), 4);
  EXPECT_EQ(color->GetRasterXSize(), dsm->GetRasterXSize());
  EXPECT_EQ(color->GetRasterYSize(), dsm->GetRasterYSize());
  double a[6], b[6];
  ASSERT_EQ(dsm->GetGeoTransform(a), CE_None);
  ASSERT_EQ(color->GetGeoTransform(b), CE_None);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(a[i], b[i]) << i;
  ASSERT_TRUE(dsm->GetSpatialRef() && color->GetSpatialRef());
  EXPECT_TRUE(color->GetSpatialRef()->IsSame(dsm->GetSpatialRef()));

  // The world file places the PNG's pixels on the same ground, k per cell.
  std::ifstream in(out / "dsm.pgw");
  std::vector<double> w;
  for (double x; in >> x;) w.push_back(x);
  ASSERT_EQ(w.size(), 6u);
  const double k = a[1] / w[0];
  EXPECT_NEAR(k, std::round(k), 1e-9);
  EXPECT_GE(k, 1);
  EXPECT_DOUBLE_EQ(w[3], -w[0]);
  EXPECT_DOUBLE_EQ(w[4], a[0] + w[0] / 2);
  EXPECT_DOUBLE_EQ(w[5], a[3] - w[0] / 2);
  const cv::Mat png = cv::imread((out / "dsm.png").string());
  ASSERT_FALSE(png.empty());
  const int map_w = static_cast<int>(std::lround(k)) * dsm->GetRasterXSize();
  const int map_h = static_cast<int>(std::lround(k)) * dsm->GetRasterYSize();
  EXPECT_GE(std::min(map_w, map_h), 600) << "the small demo DSM is enlarged";
  EXPECT_GT(png.cols, map_w + 100) << "the legend lies right of the map";
  EXPECT_GE(png.rows, map_h);
}

// ortho.tif is a Cloud-Optimized GeoTIFF over the DSM's ground, in its CRS,
// RGB with alpha, mostly filled on the simulated block; the PNG and its world
// file show it whole.
TEST_F(CliRunOutputsTest, OrthoIsACogOnTheDsmsGround) {
  const fs::path out = Out("1.2");
  GDALAllRegister();
  std::unique_ptr<GDALDataset> dsm(GDALDataset::Open((out / "dsm.tif").c_str(), GDAL_OF_RASTER));
  std::unique_ptr<GDALDataset> ortho(
      GDALDataset::Open((out / "ortho.tif").c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(dsm && ortho);
  for (GDALDataset* ds : {dsm.get(), ortho.get()}) {
    const char* layout = ds->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE");
    EXPECT_STREQ(layout ? layout : "", "COG") << ds->GetDescription();
  }
  ASSERT_EQ(ortho->GetRasterCount(), 4);
  EXPECT_EQ(ortho->GetRasterBand(4)->GetColorInterpretation(), GCI_AlphaBand);
  ASSERT_TRUE(dsm->GetSpatialRef() && ortho->GetSpatialRef());
  EXPECT_TRUE(ortho->GetSpatialRef()->IsSame(dsm->GetSpatialRef()));
  double a[6], b[6];
  ASSERT_EQ(dsm->GetGeoTransform(a), CE_None);
  ASSERT_EQ(ortho->GetGeoTransform(b), CE_None);
  EXPECT_EQ(a[0], b[0]);
  EXPECT_EQ(a[3], b[3]);
  EXPECT_LT(b[1], a[1]) << "the ortho's cells are finer than the DSM's";
  EXPECT_NEAR(ortho->GetRasterXSize() * b[1], dsm->GetRasterXSize() * a[1], b[1]);
  const int w = ortho->GetRasterXSize(), h = ortho->GetRasterYSize();
  std::vector<uint8_t> alpha(static_cast<size_t>(w) * h);
  ASSERT_EQ(
      ortho->GetRasterBand(4)->RasterIO(GF_Read, 0, 0, w, h, alpha.data(), w, h, GDT_Byte, 0, 0),
      CE_None);
  size_t filled = 0;
  for (const uint8_t v : alpha) filled += v == 255;
  // The DSM of the demo block covers about four fifths of its extent.
  EXPECT_GT(static_cast<double>(filled) / alpha.size(), 0.5);
  const nlohmann::json report = nlohmann::json::parse(test::Slurp(out / "report.json"));
  EXPECT_NEAR(report.at("ortho").at("filled_share").get<double>(),
              static_cast<double>(filled) / alpha.size(), 1e-9);
  EXPECT_DOUBLE_EQ(report.at("ortho").at("cell").get<double>(), b[1]);

  const cv::Mat png = cv::imread((out / "ortho.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(png.channels(), 4);
  std::ifstream in(out / "ortho.pgw");
  std::vector<double> world;
  for (double x; in >> x;) world.push_back(x);
  ASSERT_EQ(world.size(), 6u);
  EXPECT_NEAR(png.cols * world[0], w * b[1], world[0]);
  EXPECT_DOUBLE_EQ(world[4], b[0] + world[0] / 2);
}

// The demo block's ortho against the simulator's true orthophoto: where it
// lies (phase correlation in tiles) and whether roofs stay on their
// footprints where the run's DSM is right.
TEST_F(CliRunOutputsTest, OrthoFollowsTheTruth) {
  const fs::path out = Out("1.2");
  const fs::path truth = test::Simulated("tiny", 1) / "truth";
  const GeoRaster run_dsm = ReadGeoRaster(out / "dsm.tif");
  OrthoTruthOptions options;
  options.tile = 32;  // the demo block is small
  const OrthoTruth r =
      CompareOrthoToTruth(ReadColorRaster(out / "ortho.tif"), ReadColorRaster(truth / "ortho.tif"),
                          ReadGeoRaster(truth / "dsm.tif"), options, &run_dsm);
  ASSERT_GE(r.tiles_used, 3);  // 5 of 12 at 32 cells
  EXPECT_LE(r.shift_median, 0.5);
  EXPECT_LE(r.shift_p95, 1.5);
  EXPECT_LT(std::abs(r.luminance_bias), 5);
  ASSERT_GE(r.high_right.cells, 50);
  EXPECT_LE(r.high_right.Share(), 0.05);
}

// report.html of a real run: self-contained, and a browser decodes every
// picture in it (the DSM and the orthophoto at least) and logs nothing.
TEST_F(CliRunOutputsTest, ReportOpensInABrowser) {
  const fs::path html = Out("1.2") / "report.html";
  ASSERT_TRUE(fs::exists(html));
  const std::string page = test::Slurp(html);
  EXPECT_EQ(page.find("src=\"http"), std::string::npos);
  EXPECT_EQ(page.find("href=\"http"), std::string::npos);
  size_t pictures = 0;
  for (size_t at = page.find("<img "); at != std::string::npos; at = page.find("<img ", at + 1)) {
    ++pictures;
  }
  EXPECT_GE(pictures, 2u);
  const test::BrowserPage loaded = test::LoadInHeadlessBrowser(html);
  SAPMVS_REQUIRE_BROWSER(loaded);
  const std::string want =
      "data-pictures-decoded=\"" + std::to_string(pictures) + "/" + std::to_string(pictures) + "\"";
  EXPECT_NE(loaded.dom.find(want), std::string::npos) << want;
  EXPECT_TRUE(loaded.console.empty()) << loaded.console.front();
}

}  // namespace
}  // namespace sapmvs

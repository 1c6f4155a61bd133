// The DSM's pictures: dsm_color.tif on the DSM's grid and CRS, dsm.png with
// its world file and legend, heights coloured with a hue that falls steadily.
#include "sapmvs/run/dsm_picture.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

class DsmPictureTest : public test::ScratchTest {};

// Hue in degrees (0 red, 120 green, 240 blue); -1 for grey.
double Hue(double r, double g, double b) {
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b}), d = mx - mn;
  if (d < 8) return -1;
  double h = mx == r   ? std::fmod((g - b) / d + 6, 6.0)
             : mx == g ? (b - r) / d + 2
                       : (r - g) / d + 4;
  return 60 * h;
}

// Heights rising eastwards with a ridge, and a hole of nodata.
GeoRaster SlopeDsm(int w, int h) {
  GeoRaster r;
  r.width = w;
  r.height = h;
  r.origin_x = 500000;
  r.origin_y = 5400000;
  r.cell_size = 0.5;
  r.crs = "EPSG:32632";
  r.values.resize(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) r.at(x, y) = 300 + 0.4f * x + 2 * std::sin(0.3f * y);
  }
  r.at(w / 2, h / 2) = std::nanf("");
  return r;
}

std::vector<double> WorldFile(const fs::path& path) {
  std::ifstream in(path);
  std::vector<double> v;
  for (double x; in >> x;) v.push_back(x);
  return v;
}

TEST_F(DsmPictureTest, GeoTiffHasTheDsmsGridAndCrsAndHueFallsWithHeight) {
  const GeoRaster dsm = SlopeDsm(127, 51);
  const DsmPictures p = WriteDsmPictures(dsm, dir_ / "dsm_color.tif", dir_ / "dsm.png");
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(p.color_tif.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  ASSERT_TRUE(ds);
  ASSERT_EQ(ds->GetRasterCount(), 4);
  EXPECT_EQ(ds->GetRasterBand(4)->GetColorInterpretation(), GCI_AlphaBand);
  EXPECT_EQ(ds->GetRasterXSize(), dsm.width);
  EXPECT_EQ(ds->GetRasterYSize(), dsm.height);
  double geo[6];
  ASSERT_EQ(ds->GetGeoTransform(geo), CE_None);
  EXPECT_EQ(geo[0], dsm.origin_x);
  EXPECT_EQ(geo[1], dsm.cell_size);
  EXPECT_EQ(geo[3], dsm.origin_y);
  EXPECT_EQ(geo[5], -dsm.cell_size);
  OGRSpatialReference expected;
  expected.SetFromUserInput("EPSG:32632");
  ASSERT_TRUE(ds->GetSpatialRef());
  EXPECT_TRUE(ds->GetSpatialRef()->IsSame(&expected));

  std::vector<uint8_t> rgba(4 * dsm.values.size());
  ASSERT_EQ(ds->RasterIO(GF_Read, 0, 0, dsm.width, dsm.height, rgba.data(), dsm.width, dsm.height,
                         GDT_Byte, 4, nullptr, 4, 4 * dsm.width, 1),
            CE_None);
  // Nodata is transparent; every other cell opaque and coloured.
  std::vector<std::pair<double, double>> height_hue;
  for (int i = 0; i < dsm.width * dsm.height; ++i) {
    const uint8_t* c = &rgba[4 * i];
    if (std::isnan(dsm.values[i])) {
      EXPECT_EQ(c[3], 0) << i;
      continue;
    }
    ASSERT_EQ(c[3], 255) << i;
    height_hue.push_back({dsm.values[i], Hue(c[0], c[1], c[2])});
  }
  // The median hue of ten height bins falls from bin to bin (blue to red).
  std::sort(height_hue.begin(), height_hue.end());
  double previous = 361;
  const size_t bins = 10, n = height_hue.size();
  for (size_t b = 0; b < bins; ++b) {
    std::vector<double> hues;
    for (size_t i = b * n / bins; i < (b + 1) * n / bins; ++i) hues.push_back(height_hue[i].second);
    std::nth_element(hues.begin(), hues.begin() + hues.size() / 2, hues.end());
    const double median = hues[hues.size() / 2];
    EXPECT_LT(median, previous) << "bin " << b;
    previous = median;
  }
  EXPECT_GT(height_hue.front().second, 200) << "lowest cells are blue";
  EXPECT_LT(height_hue.back().second, 20) << "highest cells are red";
}

TEST_F(DsmPictureTest, PngIsEnlargedWithAWorldFileForTheMapAndALegend) {
  const GeoRaster dsm = SlopeDsm(127, 51);
  const DsmPictures p = WriteDsmPictures(dsm, dir_ / "dsm_color.tif", dir_ / "dsm.png");
  EXPECT_EQ(p.world_file, dir_ / "dsm.pgw");
  const cv::Mat png = cv::imread(p.png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  // 51 rows: enlarged 12 times to 612 >= 600 px.
  const int k = 12;
  EXPECT_EQ(png.rows, 51 * k);
  ASSERT_GT(png.cols, 127 * k + 100) << "room for the legend";
  const std::vector<double> w = WorldFile(p.world_file);
  ASSERT_EQ(w.size(), 6u);
  EXPECT_DOUBLE_EQ(w[0], dsm.cell_size / k);
  EXPECT_EQ(w[1], 0);
  EXPECT_EQ(w[2], 0);
  EXPECT_DOUBLE_EQ(w[3], -dsm.cell_size / k);
  EXPECT_DOUBLE_EQ(w[4], dsm.origin_x + dsm.cell_size / k / 2);
  EXPECT_DOUBLE_EQ(w[5], dsm.origin_y - dsm.cell_size / k / 2);

  // The world file's pixel of a cell centre shows the GeoTIFF's colour of
  // that cell.
  GDALAllRegister();
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(p.color_tif.c_str(), GDAL_OF_RASTER));
  ASSERT_TRUE(ds);
  for (const auto& [col, row] : std::vector<std::pair<int, int>>{{0, 0}, {126, 50}, {40, 17}}) {
    uint8_t rgb[3];
    ASSERT_EQ(ds->RasterIO(GF_Read, col, row, 1, 1, rgb, 1, 1, GDT_Byte, 3, nullptr, 3, 3, 1),
              CE_None);
    const Eigen::Vector2d centre = dsm.CellCenter(col, row);
    const int px = static_cast<int>(std::lround((centre.x() - w[4]) / w[0]));
    const int py = static_cast<int>(std::lround((centre.y() - w[5]) / w[3]));
    const cv::Vec3b got = png.at<cv::Vec3b>(py, px);
    EXPECT_EQ(got, cv::Vec3b(rgb[2], rgb[1], rgb[0])) << col << "," << row;
  }

  // The legend's colour bar: the margin's column with the most coloured
  // pixels; down it the hue rises from red (the highest heights) to blue.
  int best = -1, best_count = 0;
  for (int x = 127 * k; x < png.cols; ++x) {
    int count = 0;
    for (int y = 0; y < png.rows; ++y) {
      const cv::Vec3b c = png.at<cv::Vec3b>(y, x);
      count += Hue(c[2], c[1], c[0]) >= 0;
    }
    if (count > best_count) best = x, best_count = count;
  }
  ASSERT_GT(best_count, 150) << "no colour bar in the legend";
  double previous = -1, first = -1;
  for (int y = 0; y < png.rows; ++y) {
    const cv::Vec3b c = png.at<cv::Vec3b>(y, best);
    const double h = Hue(c[2], c[1], c[0]);
    if (h < 0) continue;
    if (first < 0) first = h;
    EXPECT_GE(h, previous - 1.5) << "row " << y;
    previous = std::max(previous, h);
  }
  EXPECT_LT(first, 20);
  EXPECT_GT(previous, 200);
  // Text and the scale bar: black pixels in the margin.
  int black = 0;
  for (int y = 0; y < png.rows; ++y) {
    for (int x = 127 * k; x < png.cols; ++x) black += png.at<cv::Vec3b>(y, x) == cv::Vec3b(0, 0, 0);
  }
  EXPECT_GT(black, 200);
}

// Without a CRS the legend says "height (local frame units)": the margin
// widens so that the whole title fits, with white beyond it.
TEST_F(DsmPictureTest, TheLegendFitsItsLongestLabel) {
  for (const std::string crs : {"EPSG:32632", ""}) {
    GeoRaster dsm = SlopeDsm(127, 51);
    dsm.crs = crs;
    const DsmPictures p = WriteDsmPictures(dsm, dir_ / "dsm_color.tif", dir_ / "dsm.png");
    const cv::Mat png = cv::imread(p.png.string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(png.empty());
    // The title's rows, right of the map: the last dark pixel of its text.
    int last_dark = 0;
    for (int y = 8; y < 32; ++y) {
      for (int x = 127 * 12; x < png.cols; ++x) {
        if (png.at<uint8_t>(y, x) < 128) last_dark = std::max(last_dark, x);
      }
    }
    EXPECT_GT(last_dark, 127 * 12 + 100) << "'" << crs << "': a title";
    EXPECT_LT(last_dark, png.cols - 8) << "'" << crs << "': the title is cut";
  }
}

TEST_F(DsmPictureTest, ALargeDsmIsNotEnlargedAndAnEmptyOneWritesNothing) {
  const GeoRaster dsm = SlopeDsm(700, 650);
  const DsmPictures p = WriteDsmPictures(dsm, dir_ / "c.tif", dir_ / "d.png");
  EXPECT_EQ(cv::imread(p.png.string()).rows, 650);
  EXPECT_DOUBLE_EQ(WorldFile(p.world_file)[0], dsm.cell_size);

  GeoRaster none = SlopeDsm(20, 10);
  for (float& v : none.values) v = std::nanf("");
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  EXPECT_THROW(WriteDsmPictures(none, empty / "c.tif", empty / "d.png"), Error);
  EXPECT_TRUE(fs::is_empty(empty));
  DsmPictureOptions bad;
  bad.min_short_side = 0;
  EXPECT_NE(bad.Problem().find("min_short_side"), std::string::npos);
  EXPECT_THROW(WriteDsmPictures(dsm, empty / "c.tif", empty / "d.png", bad), Error);
  EXPECT_TRUE(fs::is_empty(empty));
}

}  // namespace
}  // namespace sapmvs

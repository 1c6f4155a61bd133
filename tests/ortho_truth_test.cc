// The orthophoto checks of profiling/ortho_truth (ortho_truth_metrics.h) on
// a made-up truth: textured ground with one 10 m building, and orthos made
// from it wrong on purpose (shifted, too bright, roofs on the ground).
#include "ortho_truth_metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

// 256 x 256 cells of 0.25 m; the building covers cells 96..159 both ways.
constexpr int kOrthoSide = 256, kRoofFirst = 96, kRoofLast = 159;

bool OnOrthoRoof(int col, int row) {
  return col >= kRoofFirst && col <= kRoofLast && row >= kRoofFirst && row <= kRoofLast;
}

struct OrthoScene {
  ColorRaster truth;
  GeoRaster dsm;
};

OrthoScene MakeOrthoScene() {
  OrthoScene s;
  GeoRaster& g = s.truth.grid;
  g.width = g.height = kOrthoSide;
  g.cell_size = 0.25;
  g.origin_x = 500000;
  g.origin_y = 5400064;
  s.dsm = g;
  s.dsm.values.assign(static_cast<size_t>(kOrthoSide) * kOrthoSide, 0.f);
  // Smooth random texture, so that phase correlation has something to lock on.
  cv::Mat noise(kOrthoSide, kOrthoSide, CV_32F);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0, 1);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
  cv::Scalar mean, stddev;
  cv::meanStdDev(noise, mean, stddev);
  s.truth.rgba.assign(static_cast<size_t>(kOrthoSide) * kOrthoSide * 4, 255);
  for (int r = 0; r < kOrthoSide; ++r) {
    for (int c = 0; c < kOrthoSide; ++c) {
      const double t = 20 * (noise.at<float>(r, c) - mean[0]) / stddev[0];
      const bool roof = OnOrthoRoof(c, r);
      const double base[3] = {roof ? 170. : 80., roof ? 70. : 130., roof ? 60. : 70.};
      uint8_t* px = &s.truth.rgba[(static_cast<size_t>(r) * kOrthoSide + c) * 4];
      for (int k = 0; k < 3; ++k) px[k] = cv::saturate_cast<uint8_t>(base[k] + t);
      if (roof) s.dsm.at(c, r) = 10;
    }
  }
  return s;
}

uint8_t* OrthoPixel(ColorRaster& r, int col, int row) {
  return &r.rgba[(static_cast<size_t>(row) * r.grid.width + col) * 4];
}

// `in` moved by (dc, dr) cells (east, south) on the same grid; the cells
// nothing moved into are empty.
ColorRaster MovedOrtho(const ColorRaster& in, int dc, int dr) {
  ColorRaster out = in;
  const GeoRaster& g = in.grid;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      const int sc = c - dc, sr = r - dr;
      uint8_t* px = OrthoPixel(out, c, r);
      if (sc < 0 || sr < 0 || sc >= g.width || sr >= g.height) {
        std::fill(px, px + 4, 0);
        continue;
      }
      std::copy_n(&in.rgba[(static_cast<size_t>(sr) * g.width + sc) * 4], 4, px);
    }
  }
  return out;
}

// The mean of 2 x 2 cells: the truth at twice its cell, as a run at
// pyramid level 1 makes it.
ColorRaster HalvedOrtho(const ColorRaster& in) {
  ColorRaster out;
  out.grid = in.grid;
  out.grid.width /= 2;
  out.grid.height /= 2;
  out.grid.cell_size *= 2;
  out.rgba.assign(static_cast<size_t>(out.grid.width) * out.grid.height * 4, 255);
  for (int r = 0; r < out.grid.height; ++r) {
    for (int c = 0; c < out.grid.width; ++c) {
      for (int k = 0; k < 3; ++k) {
        int sum = 0;
        for (int i = 0; i < 4; ++i)
          sum +=
              in.rgba[((static_cast<size_t>(2 * r + i / 2)) * in.grid.width + 2 * c + i % 2) * 4 +
                      k];
        OrthoPixel(out, c, r)[k] = static_cast<uint8_t>((sum + 2) / 4);
      }
    }
  }
  return out;
}

TEST(OrthoTruth, TruthAgainstItselfIsPerfect) {
  const OrthoScene s = MakeOrthoScene();
  const OrthoTruth r = CompareOrthoToTruth(s.truth, s.truth, s.dsm);
  EXPECT_EQ(r.truth_cells, kOrthoSide * kOrthoSide);
  EXPECT_EQ(r.Coverage(), 1.0);
  EXPECT_EQ(r.luminance_median, 0);
  EXPECT_EQ(r.luminance_p95, 0);
  EXPECT_EQ(r.luminance_bias, 0);
  EXPECT_EQ(r.tiles, 16);
  EXPECT_EQ(r.tiles_used, 16);
  EXPECT_LT(r.shift_p95, 0.01);
  // Both sides of the four walls, corners aside.
  EXPECT_EQ(r.high.cells, 4 * 62 + 4);
  EXPECT_EQ(r.low.cells, 4 * 64);
  EXPECT_EQ(r.high.wrong, 0);
  EXPECT_EQ(r.low.wrong, 0);
}

TEST(OrthoTruth, ShiftedCopyShowsItsShiftInGsd) {
  const OrthoScene s = MakeOrthoScene();
  const OrthoTruth east = CompareOrthoToTruth(MovedOrtho(s.truth, 2, 0), s.truth, s.dsm);
  EXPECT_NEAR(east.shift_median, 2.0, 0.05);
  EXPECT_NEAR(east.shift_east, 2.0, 0.05);
  EXPECT_NEAR(east.shift_north, 0.0, 0.05);
  EXPECT_NEAR(east.Coverage(), 254.0 / 256, 1e-9);
  // At twice the truth's cell (a level-1 ortho), 2 cells north are 4 GSD.
  OrthoTruthOptions o;
  o.tile = 32;
  const ColorRaster halved = HalvedOrtho(s.truth);
  const OrthoTruth still = CompareOrthoToTruth(halved, s.truth, s.dsm, o);
  EXPECT_EQ(still.tiles_used, 16);
  EXPECT_LT(still.shift_median, 0.1);
  EXPECT_LT(still.luminance_median, 1.0);
  const OrthoTruth north = CompareOrthoToTruth(MovedOrtho(halved, 0, -2), s.truth, s.dsm, o);
  EXPECT_NEAR(north.shift_median, 4.0, 0.1);
  EXPECT_NEAR(north.shift_north, 4.0, 0.1);
  EXPECT_NEAR(north.shift_east, 0.0, 0.1);
}

TEST(OrthoTruth, ConstantOffsetIsTheBias) {
  const OrthoScene s = MakeOrthoScene();
  ColorRaster brighter = s.truth;
  for (size_t i = 0; i < brighter.rgba.size(); ++i) {
    if (i % 4 != 3) brighter.rgba[i] = cv::saturate_cast<uint8_t>(brighter.rgba[i] + 10);
  }
  const OrthoTruth r = CompareOrthoToTruth(brighter, s.truth, s.dsm);
  EXPECT_NEAR(r.luminance_bias, 10.0, 0.2);  // a few cells saturate
  EXPECT_NEAR(r.luminance_median, 10.0, 1e-9);
  EXPECT_LT(r.shift_p95, 0.05);
  EXPECT_EQ(r.low.wrong + r.high.wrong, 0);
}

TEST(OrthoTruth, RoofOnTheGroundBesideAWallIsGhosting) {
  const OrthoScene s = MakeOrthoScene();
  // The roof leans out by one cell over each wall, as a DSM too wide at
  // its walls puts it: the ground beside a wall shows the roof 3 cells in.
  ColorRaster leaning = s.truth;
  for (int i = kRoofFirst; i <= kRoofLast; ++i) {
    const std::pair<std::pair<int, int>, std::pair<int, int>> ring[] = {
        {{kRoofFirst - 1, i}, {kRoofFirst + 2, i}},
        {{kRoofLast + 1, i}, {kRoofLast - 2, i}},
        {{i, kRoofFirst - 1}, {i, kRoofFirst + 2}},
        {{i, kRoofLast + 1}, {i, kRoofLast - 2}}};
    for (const auto& [to, from] : ring) {
      std::copy_n(OrthoPixel(leaning, from.first, from.second), 3,
                  OrthoPixel(leaning, to.first, to.second));
    }
  }
  const OrthoTruth r = CompareOrthoToTruth(leaning, s.truth, s.dsm);
  EXPECT_EQ(r.low.cells, 4 * 64);
  EXPECT_EQ(r.low.wrong, r.low.cells);
  EXPECT_EQ(r.high.wrong, 0);
  // And the ground drawn onto the roof's rim.
  ColorRaster shrunk = s.truth;
  for (int i = kRoofFirst; i <= kRoofLast; ++i) {
    std::copy_n(OrthoPixel(shrunk, kRoofFirst - 3, i), 3, OrthoPixel(shrunk, kRoofFirst, i));
  }
  const OrthoTruth rim = CompareOrthoToTruth(shrunk, s.truth, s.dsm);
  EXPECT_EQ(rim.high.wrong, 64);
  EXPECT_EQ(rim.low.wrong, 0);
  // Each wrong cell is listed, on its side, at the roof's west edge.
  ASSERT_EQ(rim.wrong_cells.size(), 64u);
  for (const OrthoTruth::WrongCell& w : rim.wrong_cells) {
    EXPECT_TRUE(w.high);
    EXPECT_EQ(w.col, kRoofFirst);
    EXPECT_FALSE(w.dsm_right);  // no ortho DSM given
  }
  size_t listed = 0;
  for (const OrthoTruth::WrongCell& w : r.wrong_cells) listed += !w.high;
  EXPECT_EQ(listed, static_cast<size_t>(r.low.wrong));
}

TEST(OrthoTruth, RefusesOtherCrsAndBadOptions) {
  const OrthoScene s = MakeOrthoScene();
  ColorRaster other = s.truth;
  other.grid.crs = "EPSG:32633";
  ColorRaster truth = s.truth;
  truth.grid.crs = "EPSG:32632";
  EXPECT_THROW(CompareOrthoToTruth(other, truth, s.dsm), Error);
  OrthoTruthOptions o;
  o.tile = 4;
  try {
    CompareOrthoToTruth(s.truth, s.truth, s.dsm, o);
    FAIL() << "a 4-cell tile was taken";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("tile"), std::string::npos) << e.what();
  }
}

TEST(OrthoTruth, ReadsWhatWriteColorGeoTiffWrites) {
  const std::filesystem::path dir = test::ScratchDir();
  OrthoScene s = MakeOrthoScene();
  s.truth.grid.crs = "EPSG:32632";
  std::fill(OrthoPixel(s.truth, 5, 7), OrthoPixel(s.truth, 5, 7) + 4, 0);
  WriteColorGeoTiff(dir / "ortho.tif", s.truth.grid, s.truth.rgba);
  const ColorRaster back = ReadColorRaster(dir / "ortho.tif");
  EXPECT_EQ(back.rgba, s.truth.rgba);
  EXPECT_EQ(back.grid.width, kOrthoSide);
  EXPECT_EQ(back.grid.origin_x, s.truth.grid.origin_x);
  EXPECT_EQ(back.grid.origin_y, s.truth.grid.origin_y);
  EXPECT_EQ(back.grid.cell_size, s.truth.grid.cell_size);
  EXPECT_FALSE(back.Filled(5, 7));
  WriteGeoTiff(dir / "dsm.tif", s.dsm);
  test::ExpectInputError([&] { ReadColorRaster(dir / "dsm.tif"); }, "dsm.tif", 0,
                         "expected an RGB or RGBA raster (3 or 4 bands), got 1 band");
}

}  // namespace
}  // namespace sapmvs

#include "sapmvs/run/dsm_picture.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <gdal_utils.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "sapmvs/util/world_file.h"
#include "util/gdal_drivers.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace {

// Hypsometric stops, RGB, at shares of the height range. Neighbouring stops
// are less than 180 degrees of hue apart, so the hue of a straight RGB blend
// between them moves one way: the hue falls steadily from blue (low) to red
// (high), and shading (a common factor on R, G and B) keeps it.
constexpr std::array<std::array<double, 4>, 6> kStops = {{{0.0, 44, 84, 200},
                                                          {0.2, 40, 170, 200},
                                                          {0.4, 60, 180, 90},
                                                          {0.6, 225, 215, 60},
                                                          {0.8, 235, 135, 40},
                                                          {1.0, 190, 30, 30}}};
// Shade = kAmbient + (1 - kAmbient) * hillshade / 255: shadows stay readable.
constexpr double kAmbient = 0.35;
const cv::Vec3b kNodataGrey(220, 220, 220);
constexpr int kLegendWidth = 190, kLegendMinHeight = 360;
constexpr int kScaleBarMaxPixels = 150;

struct DatasetCloser {
  void operator()(GDALDatasetH ds) const { GDALClose(ds); }
};
using Dataset = std::unique_ptr<void, DatasetCloser>;

// The ramp's RGB at share t of the height range, as GDAL interpolates it.
cv::Vec3b Ramp(double t) {
  t = std::clamp(t, 0.0, 1.0);
  size_t k = 1;
  while (k + 1 < kStops.size() && kStops[k][0] < t) ++k;
  const auto &a = kStops[k - 1], &b = kStops[k];
  const double u = (t - a[0]) / (b[0] - a[0]);
  cv::Vec3b bgr;
  for (int c = 0; c < 3; ++c)
    bgr[2 - c] = cv::saturate_cast<uint8_t>(a[1 + c] + u * (b[1 + c] - a[1 + c]));
  return bgr;
}

// A MEM dataset of the DSM, for GDAL's DEM tools.
Dataset MemDsm(const GeoRaster& dsm, const std::string& file) {
  GDALDriverH mem = GDALDriver::ToHandle(GdalDriver("MEM"));
  if (!mem) throw Error(file + ": GDAL has no MEM driver");
  Dataset ds(GDALCreate(mem, "", dsm.width, dsm.height, 1, GDT_Float32, nullptr));
  if (!ds) throw Error(file + ": GDAL cannot hold the DSM in memory");
  double geo[6] = {dsm.origin_x, dsm.cell_size, 0, dsm.origin_y, 0, -dsm.cell_size};
  GDALSetGeoTransform(ds.get(), geo);
  if (!dsm.crs.empty()) GDALSetProjection(ds.get(), CrsToWkt(dsm.crs).c_str());
  GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
  GDALSetRasterNoDataValue(band, dsm.nodata);
  if (GDALRasterIO(band, GF_Write, 0, 0, dsm.width, dsm.height,
                   const_cast<float*>(dsm.values.data()), dsm.width, dsm.height, GDT_Float32, 0,
                   0) != CE_None) {
    throw Error(file + ": GDAL cannot hold the DSM in memory");
  }
  return ds;
}

// GDALDEMProcessing into a MEM dataset; `color_file` for color-relief.
Dataset DemProcessing(GDALDatasetH src, const char* what, const std::vector<std::string>& args,
                      const char* color_file, const std::string& file) {
  CPLStringList argv;
  argv.AddString("-of");
  argv.AddString("MEM");
  for (const std::string& a : args) argv.AddString(a.c_str());
  std::unique_ptr<GDALDEMProcessingOptions, void (*)(GDALDEMProcessingOptions*)> options(
      GDALDEMProcessingOptionsNew(argv.List(), nullptr), GDALDEMProcessingOptionsFree);
  if (!options) throw Error(file + ": GDAL refused the " + std::string(what) + " options");
  int usage_error = 0;
  CPLErrorReset();
  Dataset out(GDALDEMProcessing("", src, what, color_file, options.get(), &usage_error));
  if (!out || usage_error) {
    throw Error(file + ": GDAL " + what + " failed (GDAL: " + CPLGetLastErrorMsg() + ")");
  }
  return out;
}

std::vector<uint8_t> ReadBands(GDALDatasetH ds, int bands, int w, int h) {
  std::vector<uint8_t> out(static_cast<size_t>(bands) * w * h);
  if (GDALDatasetRasterIO(ds, GF_Read, 0, 0, w, h, out.data(), w, h, GDT_Byte, bands, nullptr,
                          bands, bands * w, 1) != CE_None) {
    throw Error("GDAL could not read back its DEM output");
  }
  return out;
}

// Colour relief (RGBA, nodata transparent) shaded by the hillshade.
std::vector<uint8_t> ShadedRelief(const GeoRaster& dsm, double lo, double hi,
                                  const std::string& file) {
  const Dataset src = MemDsm(dsm, file);
  // GDAL reads the colour table from a file; an in-memory one will do.
  const std::string table =
      "/vsimem/sapmvs_relief_" + FormatNumber(reinterpret_cast<uintptr_t>(&dsm), 17) + ".txt";
  std::ostringstream text;
  text.precision(17);
  text << "nv 0 0 0 0\n";
  for (const auto& s : kStops) {
    text << lo + s[0] * (hi - lo) << " " << s[1] << " " << s[2] << " " << s[3] << " 255\n";
  }
  const std::string t = text.str();
  VSILFILE* f = VSIFileFromMemBuffer(
      table.c_str(), reinterpret_cast<GByte*>(const_cast<char*>(t.data())), t.size(), FALSE);
  if (!f) throw Error(file + ": GDAL cannot hold the colour table in memory");
  VSIFCloseL(f);
  Dataset relief;
  try {
    relief = DemProcessing(src.get(), "color-relief", {"-alpha"}, table.c_str(), file);
  } catch (...) {
    VSIUnlink(table.c_str());
    throw;
  }
  VSIUnlink(table.c_str());
  std::vector<std::string> shade_args = {"-az", "315", "-alt", "45", "-compute_edges"};
  // Degrees across, metres up: GDAL's factor for a geographic DSM.
  if (CrsLinearUnit(dsm.crs) == "deg") shade_args.insert(shade_args.end(), {"-s", "111120"});
  const Dataset shade = DemProcessing(src.get(), "hillshade", shade_args, nullptr, file);

  std::vector<uint8_t> rgba = ReadBands(relief.get(), 4, dsm.width, dsm.height);
  const std::vector<uint8_t> hs = ReadBands(shade.get(), 1, dsm.width, dsm.height);
  // A cell whose hillshade is nodata (0) is shaded as flat ground.
  const double flat = std::sin(45.0 * M_PI / 180.0);
  for (size_t i = 0; i < hs.size(); ++i) {
    const double light = hs[i] > 0 ? hs[i] / 255.0 : flat;
    const double s = kAmbient + (1 - kAmbient) * light;
    for (int c = 0; c < 3; ++c) rgba[4 * i + c] = cv::saturate_cast<uint8_t>(rgba[4 * i + c] * s);
  }
  return rgba;
}

// The largest of 1, 2, 5 x 10^k at or below v.
double NiceFloor(double v) {
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * p <= v * (1 + 1e-12)) return m * p;
  }
  return p;
}

void Text(cv::Mat* img, const std::string& text, int x, int y, double scale = 0.45) {
  cv::putText(*img, text, {x, y}, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
}

// The margin the legend needs: its longest line, "height (local frame
// units)" or the scale bar's label, and room around it.
int LegendWidth(const std::string& unit) {
  int baseline = 0;
  const int title = cv::getTextSize("height (" + HeightLabel(unit) + ")", cv::FONT_HERSHEY_SIMPLEX,
                                    0.5, 1, &baseline)
                        .width;
  const int scale =
      cv::getTextSize("1000 " + LengthLabel(unit), cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline)
          .width;
  return std::max(kLegendWidth, 20 + std::max(title, scale) + 12);
}

// The legend in the margin right of the map (x0 = the map's width): colour
// bar from `lo` (bottom) to `hi` (top) with ticks, and the scale bar.
void DrawLegend(cv::Mat* img, int x0, double lo, double hi, double pixel_size,
                const std::string& unit) {
  const std::string height_unit = HeightLabel(unit);
  const int left = x0 + 20, top = 44;
  const int bar_h = std::min(400, img->rows - top - 150), bar_w = 22;
  Text(img, "height (" + height_unit + ")", left, 26, 0.5);
  for (int y = 0; y < bar_h; ++y) {
    cv::line(*img, {left, top + y}, {left + bar_w - 1, top + y},
             cv::Scalar(Ramp(1 - y / double(bar_h - 1))));
  }
  cv::rectangle(*img, {left - 1, top - 1}, {left + bar_w, top + bar_h}, cv::Scalar(0, 0, 0));
  const double step = NiceFloor((hi - lo) / 4);
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) {
    const int y = top + static_cast<int>(std::lround((hi - v) / (hi - lo) * (bar_h - 1)));
    cv::line(*img, {left + bar_w, y}, {left + bar_w + 5, y}, cv::Scalar(0, 0, 0));
    Text(img, FormatNumber(std::abs(v) < 1e-9 * step ? 0 : v, 6), left + bar_w + 9, y + 5);
  }
  int y = top + bar_h + 24;
  cv::rectangle(*img, {left, y - 10}, {left + bar_w, y}, cv::Scalar(kNodataGrey));
  Text(img, "no data", left + bar_w + 9, y);
  // Scale bar: a round distance, in two halves.
  if (unit != "deg") {
    const double length = NiceFloor(kScaleBarMaxPixels * pixel_size);
    const int px = static_cast<int>(std::lround(length / pixel_size));
    y += 40;
    cv::rectangle(*img, {left, y - 6}, {left + px / 2, y}, cv::Scalar(0, 0, 0), cv::FILLED);
    cv::rectangle(*img, {left, y - 6}, {left + px, y}, cv::Scalar(0, 0, 0));
    Text(img, FormatNumber(length, 6) + " " + LengthLabel(unit), left, y + 20);
  }
  Text(img, "north up", left, y + 44);
}

}  // namespace

std::string DsmPictureOptions::Problem() const {
  if (min_short_side < 1) {
    return "min_short_side >= 1 (min_short_side = " + std::to_string(min_short_side) + ")";
  }
  if (max_long_side < min_short_side) {
    return "max_long_side >= min_short_side (" + std::to_string(max_long_side) + " < " +
           std::to_string(min_short_side) + ")";
  }
  return "";
}

DsmPictures WriteDsmPictures(const GeoRaster& dsm, const std::filesystem::path& color_tif,
                             const std::filesystem::path& png, const DsmPictureOptions& options) {
  if (const std::string p = options.Problem(); !p.empty()) {
    throw Error(png.string() + ": expected " + p);
  }
  std::vector<float> valid;
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (!dsm.IsEmpty(c, r)) valid.push_back(dsm.at(c, r));
    }
  }
  if (valid.empty()) throw Error(png.string() + ": the DSM has no valid cell to draw");
  std::sort(valid.begin(), valid.end());
  const double lo = valid[valid.size() / 100];
  const double hi = std::max(lo + 1e-3, static_cast<double>(valid[valid.size() * 99 / 100]));
  const std::vector<uint8_t> rgba = ShadedRelief(dsm, lo, hi, color_tif.string());

  DsmPictures out{color_tif, png, std::filesystem::path(png).replace_extension(".pgw")};
  WriteColorGeoTiff(color_tif, dsm, rgba);

  // The map, enlarged by a whole factor so that the world file stays exact.
  const int short_side = std::min(dsm.width, dsm.height),
            long_side = std::max(dsm.width, dsm.height);
  int k = (options.min_short_side + short_side - 1) / short_side;
  k = std::max(1, std::min(k, options.max_long_side / long_side));
  cv::Mat cells(dsm.height, dsm.width, CV_8UC3);
  for (int i = 0; i < dsm.width * dsm.height; ++i) {
    const uint8_t* p = &rgba[4 * static_cast<size_t>(i)];
    cells.at<cv::Vec3b>(i / dsm.width, i % dsm.width) =
        p[3] ? cv::Vec3b(p[2], p[1], p[0]) : kNodataGrey;
  }
  cv::Mat map;
  cv::resize(cells, map, {}, k, k, cv::INTER_NEAREST);
  const std::string unit = CrsLinearUnit(dsm.crs);
  cv::Mat img(std::max(map.rows, kLegendMinHeight), map.cols + LegendWidth(unit), CV_8UC3,
              cv::Scalar(255, 255, 255));
  map.copyTo(img(cv::Rect(0, 0, map.cols, map.rows)));
  const double pixel = dsm.cell_size / k;
  DrawLegend(&img, map.cols, lo, hi, pixel, unit);
  const std::vector<uint8_t> bytes = EncodeImage(img, ImageEncoding::kPng, png.string());
  WriteBytesAtomically(png, bytes.data(), bytes.size());
  WriteWorldFile(out.world_file, dsm.origin_x, dsm.origin_y, pixel);
  return out;
}

}  // namespace sapmvs

#include "ortho_truth_metrics.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sapmvs/util/error.h"
#include "sapmvs/util/parallel_for.h"
#include "util/gdal_messages.h"

namespace sapmvs {
namespace {

using OrthoRgb = std::array<float, 3>;

// Rec. 601 luma of 8-bit (gamma-encoded) values, as image tools show it.
double OrthoLuminance(const OrthoRgb& c) { return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]; }

double OrthoRgbDistance(const OrthoRgb& a, const OrthoRgb& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

OrthoRgb OrthoCellColor(const ColorRaster& r, int col, int row) {
  const uint8_t* p = &r.rgba[(static_cast<size_t>(row) * r.grid.width + col) * 4];
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

// The `q` quantile of `v` (reordered); 0 when empty.
double OrthoQuantile(std::vector<double>& v, double q) {
  if (v.empty()) return 0;
  const auto nth = v.begin() + static_cast<long>(std::min(v.size() - 1, size_t(q * v.size())));
  std::nth_element(v.begin(), nth, v.end());
  return *nth;
}

// The cell of `g` that holds (x, y), or false outside it.
bool OrthoCellAt(const GeoRaster& g, double x, double y, int* col, int* row) {
  const double fc = std::floor((x - g.origin_x) / g.cell_size);
  const double fr = std::floor((g.origin_y - y) / g.cell_size);
  if (!(fc >= 0 && fr >= 0 && fc < g.width && fr < g.height)) return false;
  *col = static_cast<int>(fc);
  *row = static_cast<int>(fr);
  return true;
}

// The DSM's height at (x, y) (its cell's), NaN outside or where empty.
double OrthoDsmHeight(const GeoRaster& dsm, double x, double y) {
  int c = 0, r = 0;
  if (!OrthoCellAt(dsm, x, y, &c, &r) || dsm.IsEmpty(c, r)) return std::nan("");
  return dsm.at(c, r);
}

// The truth's colour at (x, y), bilinear between the filled cells around it;
// false where the cell holding (x, y) is outside or empty.
bool OrthoBilinear(const ColorRaster& t, double x, double y, OrthoRgb* out) {
  const GeoRaster& g = t.grid;
  int cc = 0, cr = 0;
  if (!OrthoCellAt(g, x, y, &cc, &cr) || !t.Filled(cc, cr)) return false;
  const double fx = (x - g.origin_x) / g.cell_size - 0.5, fy = (g.origin_y - y) / g.cell_size - 0.5;
  const int c0 = static_cast<int>(std::floor(fx)), r0 = static_cast<int>(std::floor(fy));
  const double ax = fx - c0, ay = fy - r0;
  double sum[3] = {0, 0, 0}, weight = 0;
  for (int dr = 0; dr <= 1; ++dr) {
    for (int dc = 0; dc <= 1; ++dc) {
      const int c = c0 + dc, r = r0 + dr;
      const double w = (dc ? ax : 1 - ax) * (dr ? ay : 1 - ay);
      if (w <= 0 || c < 0 || r < 0 || c >= g.width || r >= g.height || !t.Filled(c, r)) continue;
      const OrthoRgb v = OrthoCellColor(t, c, r);
      for (int k = 0; k < 3; ++k) sum[k] += w * v[k];
      weight += w;
    }
  }
  for (int k = 0; k < 3; ++k) (*out)[k] = static_cast<float>(sum[k] / weight);
  return true;
}

// The truth's mean colour over a square of `side` centred at (x, y), so
// that an ortho coarser than the truth is compared with what its cells
// average; false where the centre has none.
bool OrthoFootprint(const ColorRaster& t, double x, double y, double side, OrthoRgb* out) {
  if (!OrthoBilinear(t, x, y, out)) return false;
  const int k = std::max(1, static_cast<int>(std::ceil(side / t.grid.cell_size - 1e-6)));
  if (k == 1) return true;
  double sum[3] = {0, 0, 0};
  int n = 0;
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) {
      OrthoRgb v;
      if (!OrthoBilinear(t, x + ((j + 0.5) / k - 0.5) * side, y - ((i + 0.5) / k - 0.5) * side, &v))
        continue;
      for (int c = 0; c < 3; ++c) sum[c] += v[c];
      ++n;
    }
  }
  for (int c = 0; c < 3; ++c) (*out)[c] = static_cast<float>(sum[c] / n);
  return true;
}

bool OrthoSameCrs(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty() || a == b) return true;
  QuietGdalErrors quiet;
  OGRSpatialReference sa, sb;
  if (sa.SetFromUserInput(a.c_str()) != OGRERR_NONE ||
      sb.SetFromUserInput(b.c_str()) != OGRERR_NONE)
    return false;
  return sa.IsSame(&sb);
}

// The luminance of the truth's tile at (tx, ty) in `a`, the ortho's at
// (tx + ox, ty + oy) in `b`, where both are filled, less their means, 0
// elsewhere; false when fewer are filled or the truth is flatter than the
// options allow. The means go: the window of one tile would otherwise match
// the other's at no shift and pull the peak towards it (a 2-cell shift read
// 1.7).
bool OrthoTilePair(const ColorRaster& ortho, const std::vector<OrthoRgb>& truth_rgb,
                   const std::vector<uint8_t>& truth_valid, int tx, int ty, int ox, int oy,
                   const OrthoTruthOptions& o, cv::Mat* a, cv::Mat* b) {
  const int n = o.tile, w = ortho.grid.width, h = ortho.grid.height;
  cv::Mat has = cv::Mat::zeros(n, n, CV_8U);
  *a = cv::Mat::zeros(n, n, CV_64F);
  *b = cv::Mat::zeros(n, n, CV_64F);
  double sum_a = 0, sum_b = 0, sum_aa = 0;
  long filled = 0;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const int oc = tx + c + ox, orow = ty + r + oy;
      const size_t i = static_cast<size_t>(ty + r) * w + tx + c;
      if (!truth_valid[i] || oc < 0 || orow < 0 || oc >= w || orow >= h || !ortho.Filled(oc, orow))
        continue;
      const double la = OrthoLuminance(truth_rgb[i]);
      const double lb = OrthoLuminance(OrthoCellColor(ortho, oc, orow));
      a->at<double>(r, c) = la;
      b->at<double>(r, c) = lb;
      has.at<uint8_t>(r, c) = 1;
      sum_a += la, sum_b += lb, sum_aa += la * la;
      ++filled;
    }
  }
  if (filled < o.min_tile_fill * n * n || filled < 2) return false;
  const double mean_a = sum_a / filled, mean_b = sum_b / filled;
  if (std::sqrt(std::max(0.0, sum_aa / filled - mean_a * mean_a)) < o.min_texture) return false;
  cv::subtract(*a, mean_a, *a, has);
  cv::subtract(*b, mean_b, *b, has);
  return true;
}

// Phase correlation of the luminance tiles (see OrthoTruthOptions); fills
// the shift fields of `out`.
void OrthoShifts(const ColorRaster& ortho, const std::vector<OrthoRgb>& truth_rgb,
                 const std::vector<uint8_t>& truth_valid, const OrthoTruthOptions& o,
                 OrthoTruth* out) {
  const int n = o.tile;
  const double to_gsd = ortho.grid.cell_size / out->gsd;
  cv::Mat window;
  cv::createHanningWindow(window, cv::Size(n, n), CV_64F);
  std::vector<double> shifts, east, north;
  for (int ty = 0; ty + n <= ortho.grid.height; ty += n) {
    for (int tx = 0; tx + n <= ortho.grid.width; tx += n) {
      ++out->tiles;
      cv::Mat a, b;
      if (!OrthoTilePair(ortho, truth_rgb, truth_valid, tx, ty, 0, 0, o, &a, &b)) continue;
      // Where the ortho's content lies relative to the truth's: (+x, +y) =
      // east and south, in ortho cells.
      cv::Point2d d = cv::phaseCorrelate(a, b, window);
      // The content that leaves one tile and enters the other pulls the
      // estimate towards no shift (2 cells read 1.96): once more on the
      // ortho's tile moved by the whole cells found, for the rest.
      const int ox = static_cast<int>(std::lround(d.x)), oy = static_cast<int>(std::lround(d.y));
      if ((ox != 0 || oy != 0) &&
          OrthoTilePair(ortho, truth_rgb, truth_valid, tx, ty, ox, oy, o, &a, &b)) {
        d = cv::Point2d(ox, oy) + cv::phaseCorrelate(a, b, window);
      }
      ++out->tiles_used;
      shifts.push_back(std::hypot(d.x, d.y) * to_gsd);
      east.push_back(d.x * to_gsd);
      north.push_back(0.0 - d.y * to_gsd);  // 0 - 0 is +0: no "-0.00" for no shift
      out->tile_shifts.push_back({tx, ty, east.back(), north.back()});
    }
  }
  out->shift_median = OrthoQuantile(shifts, 0.5);
  out->shift_p95 = OrthoQuantile(shifts, 0.95);
  out->shift_east = OrthoQuantile(east, 0.5);
  out->shift_north = OrthoQuantile(north, 0.5);
}

// DSM cells within `radius` cells of a step higher than `step` between two
// side-by-side cells.
cv::Mat OrthoNearSteps(const GeoRaster& dsm, double step, int radius) {
  cv::Mat mask = cv::Mat::zeros(dsm.height, dsm.width, CV_8U);
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      for (const auto& [dc, dr] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (c + dc >= dsm.width || r + dr >= dsm.height || dsm.IsEmpty(c + dc, r + dr)) continue;
        if (std::abs(double(dsm.at(c, r)) - dsm.at(c + dc, r + dr)) <= step) continue;
        mask.at<uint8_t>(r, c) = 1;
        mask.at<uint8_t>(r + dr, c + dc) = 1;
      }
    }
  }
  if (radius > 0) {
    cv::dilate(
        mask, mask,
        cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1)));
  }
  return mask;
}

// The wrong-side counts of the edge cells (see OrthoTruthOptions).
void OrthoEdges(const ColorRaster& ortho, const ColorRaster& truth, const GeoRaster& dsm,
                const std::vector<OrthoRgb>& truth_rgb, const std::vector<uint8_t>& both,
                const OrthoTruthOptions& o, const GeoRaster* ortho_dsm, OrthoTruth* out) {
  const double step = o.step_gsd * out->gsd, across = o.across_gsd * out->gsd;
  // A step lies on a cell's side, half a cell from its centre.
  const int radius =
      std::max(0, static_cast<int>(std::floor(o.edge_gsd * out->gsd / dsm.cell_size - 0.5 + 1e-9)));
  const cv::Mat near = OrthoNearSteps(dsm, step, radius);
  constexpr int kDirections = 16;
  std::array<Eigen::Vector2d, kDirections> dirs;
  for (int k = 0; k < kDirections; ++k) {
    const double a = 2 * M_PI * k / kDirections;
    dirs[k] = {std::cos(a), std::sin(a)};
  }
  const GeoRaster& g = ortho.grid;
  // High, wrong, low, wrong; the same where the ortho's DSM is right; the
  // same where it is right on both sides.
  std::vector<std::array<long, 12>> rows(g.height, std::array<long, 12>{});
  std::vector<std::vector<OrthoTruth::WrongCell>> wrong_rows(g.height);
  ParallelFor(g.height, [&](long row) {
    for (int col = 0; col < g.width; ++col) {
      const size_t i = static_cast<size_t>(row) * g.width + col;
      if (!both[i]) continue;
      const Eigen::Vector2d p = g.CellCenter(col, static_cast<int>(row));
      int dc = 0, dr = 0;
      if (!OrthoCellAt(dsm, p.x(), p.y(), &dc, &dr) || !near.at<uint8_t>(dr, dc)) continue;
      const double h0 = OrthoDsmHeight(dsm, p.x(), p.y());
      std::array<double, kDirections> dh;
      int best = -1;
      for (int k = 0; k < kDirections; ++k) {
        const Eigen::Vector2d q = p + across * dirs[k];
        dh[k] = OrthoDsmHeight(dsm, q.x(), q.y()) - h0;
        if (std::isfinite(dh[k]) && (best < 0 || std::abs(dh[k]) > std::abs(dh[best]))) best = k;
      }
      if (best < 0 || !(std::abs(dh[best]) > step)) continue;
      // Along the gradient: the mean of the directions that cross the same
      // step (a wall's normal, a corner's diagonal).
      const double sign = dh[best] > 0 ? 1 : -1;
      Eigen::Vector2d along = Eigen::Vector2d::Zero();
      for (int k = 0; k < kDirections; ++k) {
        if (std::isfinite(dh[k]) && sign * dh[k] > step) along += dirs[k];
      }
      if (along.norm() < 1e-6) along = dirs[best];
      const Eigen::Vector2d q = p + across * along.normalized();
      const double hq = OrthoDsmHeight(dsm, q.x(), q.y());
      if (!(sign * (hq - h0) > step)) continue;
      OrthoRgb other;
      if (!OrthoFootprint(truth, q.x(), q.y(), g.cell_size, &other)) continue;
      const OrthoRgb& own = truth_rgb[i];
      if (OrthoRgbDistance(own, other) < o.min_contrast) continue;
      const OrthoRgb seen = OrthoCellColor(ortho, col, static_cast<int>(row));
      const bool wrong = OrthoRgbDistance(seen, other) < OrthoRgbDistance(seen, own);
      const int side = sign < 0 ? 0 : 2;  // the other side lower: this is a roof
      ++rows[row][side];
      rows[row][side + 1] += wrong;
      const double tolerance = o.dsm_tolerance_gsd * out->gsd;
      OrthoTruth::WrongCell cell{col, static_cast<int>(row), p.x(), p.y(), side == 0};
      if (ortho_dsm && std::abs(OrthoDsmHeight(*ortho_dsm, p.x(), p.y()) - h0) <= tolerance) {
        ++rows[row][4 + side];
        rows[row][4 + side + 1] += wrong;
        cell.dsm_right = true;
        if (std::abs(OrthoDsmHeight(*ortho_dsm, q.x(), q.y()) - hq) <= tolerance) {
          ++rows[row][8 + side];
          rows[row][8 + side + 1] += wrong;
          cell.step_right = true;
        }
      }
      if (wrong) wrong_rows[row].push_back(cell);
    }
  });
  for (const auto& r : rows) {
    out->high.cells += r[0], out->high.wrong += r[1];
    out->low.cells += r[2], out->low.wrong += r[3];
    out->high_right.cells += r[4], out->high_right.wrong += r[5];
    out->low_right.cells += r[6], out->low_right.wrong += r[7];
    out->high_step_right.cells += r[8], out->high_step_right.wrong += r[9];
    out->low_step_right.cells += r[10], out->low_step_right.wrong += r[11];
  }
  for (const auto& r : wrong_rows)
    out->wrong_cells.insert(out->wrong_cells.end(), r.begin(), r.end());
}

}  // namespace

std::string OrthoTruthOptions::Problem() const { return FirstRangeProblem(*this); }

ColorRaster ReadColorRaster(const std::filesystem::path& path) {
  ColorRaster out;
  out.grid = ReadGeoRaster(path);  // the grid's checks and CRS; registers GDAL's drivers
  out.grid.values.clear();
  out.grid.values.shrink_to_fit();
  const std::string file = path.string();
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) throw InputError(file, 0, "cannot open it again to read its colours");
  const int bands = ds->GetRasterCount();
  if (bands != 3 && bands != 4) {
    throw InputError(file, 0,
                     "expected an RGB or RGBA raster (3 or 4 bands), got " + std::to_string(bands) +
                         " band" + (bands == 1 ? "" : "s"));
  }
  for (int b = 1; b <= bands; ++b) {
    if (ds->GetRasterBand(b)->GetRasterDataType() != GDT_Byte) {
      throw InputError(file, 0,
                       "expected 8-bit bands, band " + std::to_string(b) + " is " +
                           GDALGetDataTypeName(ds->GetRasterBand(b)->GetRasterDataType()));
    }
  }
  const int w = out.grid.width, h = out.grid.height;
  out.rgba.assign(static_cast<size_t>(w) * h * 4, 255);
  int band_map[4] = {1, 2, 3, 4};
  if (ds->RasterIO(GF_Read, 0, 0, w, h, out.rgba.data(), w, h, GDT_Byte, bands, band_map, 4, 4L * w,
                   1, nullptr) != CE_None) {
    throw InputError(file, 0, "cannot read its " + std::to_string(bands) + " bands");
  }
  double geo[6];
  if (ds->GetGeoTransform(geo) == CE_None && geo[5] > 0) {  // south-up, as ReadGeoRaster flips
    for (int r = 0; r < h / 2; ++r) {
      std::swap_ranges(out.rgba.begin() + 4L * w * r, out.rgba.begin() + 4L * w * (r + 1),
                       out.rgba.begin() + 4L * w * (h - 1 - r));
    }
  }
  return out;
}

OrthoTruth CompareOrthoToTruth(const ColorRaster& ortho, const ColorRaster& truth,
                               const GeoRaster& dsm, const OrthoTruthOptions& options,
                               const GeoRaster* ortho_dsm) {
  if (const std::string problem = options.Problem(); !problem.empty())
    throw Error("expected " + problem);
  if (!OrthoSameCrs(ortho.grid.crs, truth.grid.crs) || !OrthoSameCrs(dsm.crs, truth.grid.crs))
    throw Error("expected the CRS of the true ortho and its DSM");
  const GeoRaster& g = ortho.grid;
  const GeoRaster& t = truth.grid;
  const bool overlap = g.origin_x < t.origin_x + t.width * t.cell_size &&
                       t.origin_x < g.origin_x + g.width * g.cell_size &&
                       g.origin_y - g.height * g.cell_size < t.origin_y &&
                       t.origin_y - t.height * t.cell_size < g.origin_y;
  if (!overlap) throw Error("expected an ortho that overlaps the true ortho");
  OrthoTruth out;
  out.gsd = t.cell_size;
  out.ortho_cell = g.cell_size;

  // The truth on the ortho's grid, and where both have a colour.
  const size_t cells = static_cast<size_t>(g.width) * g.height;
  std::vector<OrthoRgb> truth_rgb(cells);
  std::vector<uint8_t> truth_valid(cells, 0), both(cells, 0);
  ParallelFor(g.height, [&](long row) {
    for (int col = 0; col < g.width; ++col) {
      const size_t i = static_cast<size_t>(row) * g.width + col;
      const Eigen::Vector2d p = g.CellCenter(col, static_cast<int>(row));
      truth_valid[i] = OrthoFootprint(truth, p.x(), p.y(), g.cell_size, &truth_rgb[i]);
      both[i] = truth_valid[i] && ortho.Filled(col, static_cast<int>(row));
    }
  });

  for (int r = 0; r < t.height; ++r) {
    for (int c = 0; c < t.width; ++c) {
      if (!truth.Filled(c, r)) continue;
      ++out.truth_cells;
      const Eigen::Vector2d p = t.CellCenter(c, r);
      int oc = 0, orow = 0;
      out.covered_cells += OrthoCellAt(g, p.x(), p.y(), &oc, &orow) && ortho.Filled(oc, orow);
    }
  }

  std::vector<double> abs_diff;
  double signed_sum = 0;
  for (int r = 0; r < g.height; ++r) {
    for (int c = 0; c < g.width; ++c) {
      const size_t i = static_cast<size_t>(r) * g.width + c;
      if (!both[i]) continue;
      const double d = OrthoLuminance(OrthoCellColor(ortho, c, r)) - OrthoLuminance(truth_rgb[i]);
      abs_diff.push_back(std::abs(d));
      signed_sum += d;
    }
  }
  out.compared_cells = static_cast<long>(abs_diff.size());
  if (!abs_diff.empty()) out.luminance_bias = signed_sum / abs_diff.size();
  out.luminance_median = OrthoQuantile(abs_diff, 0.5);
  out.luminance_p95 = OrthoQuantile(abs_diff, 0.95);

  OrthoShifts(ortho, truth_rgb, truth_valid, options, &out);
  OrthoEdges(ortho, truth, dsm, truth_rgb, both, options, ortho_dsm, &out);
  return out;
}

}  // namespace sapmvs

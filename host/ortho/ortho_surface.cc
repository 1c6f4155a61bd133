#include "ortho/ortho_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "sapmvs/util/parallel_for.h"

namespace sapmvs {
namespace {

constexpr double kMaxOrthoCells = 268435456.0;  // 2^28, as the DSM
// Heights that differ by more than this many cells from one cell to the
// next (63 degrees) are a wall: drawn as one and not interpolated across.
// Steeper than the objects' slope: a canopy's and rough ground's cells
// differ by one or two, and drawing each of those as a wall made a
// forested flight's ortho half as slow again, for colours no better on
// the simulated blocks.
constexpr double kWallSlope = 2.0;
// A hole's cells this near its rim take the nearest rim cell's height; the
// rest a low height of the rim. The points a roof's edge lacks (patches
// straddling it match neither side) leave a cell or two of hole between
// roof and ground: filled low, the roof shrank, and the images that lean
// it over the ground beside it coloured that ground with it.
constexpr float kRimCells = 1.5f;

// On the surface the depth buffers draw (OrthoDepthBuffer): where the four
// cell centres around (x, y) are valid and lie on one surface, the plane of
// the triangle it falls in, so that a point of the ortho lies on the drawn
// surface and no tolerance for its own surface hides an occluder; across a
// step higher than `step` (a roof's edge, a wall), the nearest cell's
// height, as the blocks drawn there; interpolated, a roof would lean half a
// cell over the ground at its foot and be drawn there again. Where some of
// the four are empty, bilinear from those that are not. NaN when none is
// valid.
float InterpolateHeight(const GeoRaster& dsm, double x, double y, double step) {
  const double fc = (x - dsm.origin_x) / dsm.cell_size - 0.5;
  const double fr = (dsm.origin_y - y) / dsm.cell_size - 0.5;
  const int c0 = static_cast<int>(std::floor(fc)), r0 = static_cast<int>(std::floor(fr));
  const double tx = fc - c0, ty = fr - r0;
  double sum = 0, weight = 0, nearest_w = -1;
  float lo = std::numeric_limits<float>::infinity(), hi = -lo, nearest = 0;
  std::array<float, 4> z;
  int valid = 0;
  for (int dr = 0; dr < 2; ++dr) {
    for (int dc = 0; dc < 2; ++dc) {
      const int c = std::clamp(c0 + dc, 0, dsm.width - 1);
      const int r = std::clamp(r0 + dr, 0, dsm.height - 1);
      z[2 * dr + dc] = dsm.at(c, r);
      if (dsm.IsEmpty(c, r)) continue;
      ++valid;
      const double w = (dc ? tx : 1 - tx) * (dr ? ty : 1 - ty) + 1e-9;
      sum += w * z[2 * dr + dc];
      weight += w;
      lo = std::min(lo, z[2 * dr + dc]);
      hi = std::max(hi, z[2 * dr + dc]);
      if (w > nearest_w) {
        nearest_w = w;
        nearest = z[2 * dr + dc];
      }
    }
  }
  if (!(weight > 0)) return std::numeric_limits<float>::quiet_NaN();
  if (hi - lo > step) return nearest;
  if (valid < 4) return static_cast<float>(sum / weight);
  // The triangles split the quad along the diagonal from (c0 + 1, r0) to
  // (c0, r0 + 1).
  if (tx + ty <= 1) return static_cast<float>(z[0] + tx * (z[1] - z[0]) + ty * (z[2] - z[0]));
  return static_cast<float>(z[3] + (1 - tx) * (z[2] - z[3]) + (1 - ty) * (z[1] - z[3]));
}

void FindObjects(const GeoRaster& dsm, double object_slope, double margin, OrthoSurface* s) {
  const double step = object_slope * dsm.cell_size;
  cv::Mat steep(dsm.height, dsm.width, CV_8U, cv::Scalar(0));
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      const float z = dsm.at(c, r);
      const bool right =
          c + 1 < dsm.width && !dsm.IsEmpty(c + 1, r) && std::abs(dsm.at(c + 1, r) - z) > step;
      const bool below =
          r + 1 < dsm.height && !dsm.IsEmpty(c, r + 1) && std::abs(dsm.at(c, r + 1) - z) > step;
      // Both cells of a step: the roof's edge and the ground at its foot.
      if (right) steep.at<uint8_t>(r, c) = steep.at<uint8_t>(r, c + 1) = 255;
      if (below) steep.at<uint8_t>(r, c) = steep.at<uint8_t>(r + 1, c) = 255;
    }
  }
  // A roof is flat inside its edges: filling the holes of the edges' mask
  // makes it one object with them. Closing joins the broken outline first.
  cv::morphologyEx(steep, steep, cv::MORPH_CLOSE,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  cv::Mat outside = steep.clone();
  cv::Mat pad(dsm.height + 2, dsm.width + 2, CV_8U, cv::Scalar(0));
  outside.copyTo(pad(cv::Rect(1, 1, dsm.width, dsm.height)));
  cv::floodFill(pad, cv::Point(0, 0), cv::Scalar(128));
  const cv::Mat inner = pad(cv::Rect(1, 1, dsm.width, dsm.height));
  steep.setTo(255, inner == 0);
  const int grow = static_cast<int>(std::ceil(margin / dsm.cell_size));
  if (grow > 0) {
    cv::dilate(steep, steep,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * grow + 1, 2 * grow + 1)));
  }
  cv::Mat labels;
  const int n = cv::connectedComponents(steep, labels, 8, CV_32S);
  s->objects = n - 1;
  s->dsm_object.resize(static_cast<size_t>(dsm.width) * dsm.height);
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c)
      s->dsm_object[static_cast<size_t>(r) * dsm.width + c] = labels.at<int>(r, c) - 1;
  }
}

}  // namespace

std::vector<uint8_t> WallQuads(const GeoRaster& dsm, double step) {
  std::vector<uint8_t> walls(dsm.values.size(), 0);
  ParallelFor(dsm.height, [&](long r) {
    for (int c = 0; c < dsm.width; ++c) {
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      for (int dr = 0; dr < 2; ++dr) {
        for (int dc = 0; dc < 2; ++dc) {
          const int cc = c + dc, rr = static_cast<int>(r) + dr;
          if (cc >= dsm.width || rr >= dsm.height || dsm.IsEmpty(cc, rr)) continue;
          lo = std::min(lo, dsm.at(cc, rr));
          hi = std::max(hi, dsm.at(cc, rr));
        }
      }
      walls[static_cast<size_t>(r) * dsm.width + c] = hi - lo > step;
    }
  });
  return walls;
}

long FillEnclosedHoles(GeoRaster* dsm) {
  const int w = dsm->width, h = dsm->height;
  // Empty cells, inside a frame of empty ones; those the frame reaches lie
  // outside the surface.
  cv::Mat empty(h + 2, w + 2, CV_8U, cv::Scalar(255));
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) empty.at<uint8_t>(r + 1, c + 1) = dsm->IsEmpty(c, r) ? 255 : 0;
  }
  // Every empty cell, for the distances to the valid ones below.
  const cv::Mat invalid = empty.clone();
  cv::floodFill(empty, cv::Point(0, 0), cv::Scalar(0));
  cv::Mat labels;
  const int n = cv::connectedComponents(empty, labels, 4, CV_32S);
  if (n <= 1) return 0;
  std::vector<std::vector<float>> rim(n);
  for (int r = 1; r <= h; ++r) {
    for (int c = 1; c <= w; ++c) {
      if (labels.at<int>(r, c) != 0 || dsm->IsEmpty(c - 1, r - 1)) continue;
      for (const auto& [dr, dc] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int hole = labels.at<int>(r + dr, c + dc);
        if (hole > 0) rim[hole].push_back(dsm->at(c - 1, r - 1));
      }
    }
  }
  std::vector<float> fill(n, std::numeric_limits<float>::quiet_NaN());
  for (int i = 1; i < n; ++i) {
    if (rim[i].empty()) continue;
    auto at = rim[i].begin() + rim[i].size() / 10;
    std::nth_element(rim[i].begin(), at, rim[i].end());
    fill[i] = *at;
  }
  // The nearest valid cell of each empty one (its label's), for the cells
  // at a hole's rim.
  cv::Mat distance, nearest;
  cv::distanceTransform(invalid, distance, nearest, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<float> height_of(static_cast<size_t>(h) * w + 1,
                               std::numeric_limits<float>::quiet_NaN());
  for (int r = 1; r <= h; ++r) {
    for (int c = 1; c <= w; ++c) {
      if (!dsm->IsEmpty(c - 1, r - 1)) height_of[nearest.at<int>(r, c)] = dsm->at(c - 1, r - 1);
    }
  }
  long filled = 0;
  for (int r = 1; r <= h; ++r) {
    for (int c = 1; c <= w; ++c) {
      const int hole = labels.at<int>(r, c);
      if (hole == 0 || std::isnan(fill[hole])) continue;
      const float rim_height = height_of[nearest.at<int>(r, c)];
      dsm->at(c - 1, r - 1) = distance.at<float>(r, c) <= kRimCells && !std::isnan(rim_height)
                                  ? rim_height
                                  : fill[hole];
      ++filled;
    }
  }
  return filled;
}

OrthoSurface MakeOrthoSurface(const GeoRaster& source, double cell, double object_slope,
                              double margin) {
  OrthoSurface s;
  s.dsm = source;
  FillEnclosedHoles(&s.dsm);
  const GeoRaster& dsm = s.dsm;
  GeoRaster& g = s.grid;
  g.origin_x = dsm.origin_x;
  g.origin_y = dsm.origin_y;
  g.cell_size = cell;
  g.crs = dsm.crs;
  const double w = std::ceil(dsm.width * dsm.cell_size / cell - 1e-6);
  const double h = std::ceil(dsm.height * dsm.cell_size / cell - 1e-6);
  if (w * h > kMaxOrthoCells) {
    throw Error("orthophoto: " + FormatNumber(w, 12) + " x " + FormatNumber(h, 12) + " cells of " +
                FormatNumber(cell, 6) +
                " (expected at most 2^28 cells: give a larger --ortho-cell)");
  }
  g.width = static_cast<int>(w);
  g.height = static_cast<int>(h);
  g.values.resize(static_cast<size_t>(g.width) * g.height);
  s.dsm_col.resize(g.width);
  s.dsm_row.resize(g.height);
  const double step = kWallSlope * dsm.cell_size;
  s.walls = WallQuads(dsm, step);
  for (int c = 0; c < g.width; ++c) {
    s.dsm_col[c] = std::min(dsm.width - 1, static_cast<int>((c + 0.5) * cell / dsm.cell_size));
  }
  for (int r = 0; r < g.height; ++r) {
    s.dsm_row[r] = std::min(dsm.height - 1, static_cast<int>((r + 0.5) * cell / dsm.cell_size));
  }
  ParallelFor(g.height, [&](long r) {
    for (int c = 0; c < g.width; ++c) {
      const Eigen::Vector2d p = g.CellCenter(c, static_cast<int>(r));
      g.at(c, static_cast<int>(r)) = InterpolateHeight(dsm, p.x(), p.y(), step);
    }
  });
  s.zmin = std::numeric_limits<double>::infinity();
  s.zmax = -s.zmin;
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      s.zmin = std::min<double>(s.zmin, dsm.at(c, r));
      s.zmax = std::max<double>(s.zmax, dsm.at(c, r));
    }
  }
  FindObjects(dsm, object_slope, margin, &s);
  return s;
}

CellWindow ImageWindow(const Camera& camera, const GeoRaster& grid, double zmin, double zmax) {
  CellWindow all{0, 0, grid.width, grid.height};
  const Eigen::Vector3d& o = camera.center();
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  const double w = camera.width() - 0.5, h = camera.height() - 0.5;
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(w, -0.5),
                                    Eigen::Vector2d(-0.5, h), Eigen::Vector2d(w, h)}) {
    const Eigen::Vector3d d = camera.Ray(uv);
    for (const double z : {zmin, zmax}) {
      const double t = (z - o.z()) / d.z();
      if (!(d.z() < 0) || !(t > 0)) return all;
      const Eigen::Vector3d p = o + t * d;
      x0 = std::min(x0, p.x());
      x1 = std::max(x1, p.x());
      y0 = std::min(y0, p.y());
      y1 = std::max(y1, p.y());
    }
  }
  CellWindow win;
  win.col0 = std::max(0, static_cast<int>(std::floor((x0 - grid.origin_x) / grid.cell_size)));
  win.col1 =
      std::min(grid.width, static_cast<int>(std::ceil((x1 - grid.origin_x) / grid.cell_size)) + 1);
  win.row0 = std::max(0, static_cast<int>(std::floor((grid.origin_y - y1) / grid.cell_size)));
  win.row1 =
      std::min(grid.height, static_cast<int>(std::ceil((grid.origin_y - y0) / grid.cell_size)) + 1);
  return win;
}

}  // namespace sapmvs

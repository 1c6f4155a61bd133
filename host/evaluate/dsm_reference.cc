#include "evaluate/dsm_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs {
namespace {

// Continuous cell coordinate along one axis (0 = the first centre), clamped
// to the centres; false outside [-0.5, n - 0.5].
bool AxisPosition(double t, int n, int* i0, double* f) {
  if (!(t >= -0.5 && t <= n - 0.5)) return false;
  t = std::clamp(t, 0.0, static_cast<double>(n - 1));
  *i0 = n >= 2 ? std::min(static_cast<int>(std::floor(t)), n - 2) : 0;
  *f = n >= 2 ? t - *i0 : 0.0;
  return true;
}

}  // namespace

double DsmHeight(const GeoRaster& dsm, double x, double y) {
  int c0 = 0, r0 = 0;
  double fx = 0, fy = 0;
  if (!AxisPosition((x - dsm.origin_x) / dsm.cell_size - 0.5, dsm.width, &c0, &fx) ||
      !AxisPosition((dsm.origin_y - y) / dsm.cell_size - 0.5, dsm.height, &r0, &fy)) {
    return kNaN;
  }
  const double wx[2] = {1 - fx, fx}, wy[2] = {1 - fy, fy};
  double sum = 0;
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      const double w = wx[i] * wy[j];
      // Cells without weight are not read: a value exactly at a centre next
      // to an empty cell or the raster's edge is still defined.
      if (w == 0) continue;
      if (dsm.IsEmpty(c0 + i, r0 + j)) return kNaN;
      sum += w * dsm.at(c0 + i, r0 + j);
    }
  }
  return sum;
}

long DsmCellIndex(const GeoRaster& dsm, double x, double y) {
  const double c = std::floor((x - dsm.origin_x) / dsm.cell_size);
  const double r = std::floor((dsm.origin_y - y) / dsm.cell_size);
  if (!(c >= 0 && c < dsm.width && r >= 0 && r < dsm.height)) return -1;
  return static_cast<long>(r) * dsm.width + static_cast<long>(c);
}

DsmFootprint FootprintFromBox(const GeoRaster& dsm, double xmin, double ymin, double xmax,
                              double ymax) {
  DsmFootprint f;
  f.mask.assign(dsm.values.size(), 0);
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      const Eigen::Vector2d p = dsm.CellCenter(c, r);
      f.mask[static_cast<size_t>(r) * dsm.width + c] =
          !dsm.IsEmpty(c, r) && p.x() >= xmin && p.x() <= xmax && p.y() >= ymin && p.y() <= ymax;
    }
  }
  f.note = "box X " + FormatNumber(xmin, 10) + " .. " + FormatNumber(xmax, 10) + ", Y " +
           FormatNumber(ymin, 10) + " .. " + FormatNumber(ymax, 10);
  return f;
}

DsmFootprint FootprintFromBlock(const GeoRaster& dsm, const Block& block, int min_images) {
  DsmFootprint f;
  f.mask.assign(dsm.values.size(), 0);
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      const Eigen::Vector3d x(dsm.CellCenter(c, r).x(), dsm.CellCenter(c, r).y(), dsm.at(c, r));
      int seen = 0;
      for (const BlockImage& im : block.images) {
        if (im.camera.InImage(im.camera.Project(x)) && ++seen >= min_images) break;
      }
      f.mask[static_cast<size_t>(r) * dsm.width + c] = seen >= min_images;
    }
  }
  f.note = "cells seen by at least " + std::to_string(min_images) + " of the " +
           std::to_string(block.images.size()) + " images of " + block.source.string();
  return f;
}

Completeness ComputeCompleteness(const GeoRaster& dsm, const DsmFootprint& footprint,
                                 const std::vector<Eigen::Vector3d>& points,
                                 const std::vector<double>& dz, double tolerance) {
  if (footprint.mask.size() != dsm.values.size() || dz.size() != points.size()) {
    throw Error("completeness: footprint or error sizes do not match the DSM and the cloud");
  }
  Completeness out;
  out.footprint = footprint.note;
  std::vector<uint8_t> filled(footprint.mask.size(), 0);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!(std::abs(dz[i]) <= tolerance)) continue;
    const long cell = DsmCellIndex(dsm, points[i].x(), points[i].y());
    if (cell >= 0) filled[cell] = 1;
  }
  for (size_t i = 0; i < filled.size(); ++i) {
    out.cells += footprint.mask[i] != 0;
    out.filled += footprint.mask[i] != 0 && filled[i] != 0;
  }
  if (out.cells > 0) out.share = static_cast<double>(out.filled) / out.cells;
  return out;
}

}  // namespace sapmvs

#include "sapmvs/run/cloud_dsm.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <opencv2/core.hpp>
#include <sstream>
#include <unordered_map>

#include "match/point_neighbours.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {

std::string DsmOptions::Problem() const { return FirstRangeProblem(*this); }

SpacingSum SumPointSpacing(const PointCloud& cloud, size_t stride) {
  SpacingSum sum;
  const size_t n = cloud.points.size();
  if (n < 2) return sum;
  // Relative to the first point: UTM coordinates leave no digits to spare in
  // float, which only picks the neighbour; its distance is taken in double.
  const Eigen::Vector3d o = cloud.points.front().position;
  std::vector<float> xyz(3 * n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = cloud.points[i].position - o;
    for (int c = 0; c < 3; ++c) xyz[3 * i + c] = static_cast<float>(p[c]);
  }
  std::vector<size_t> queries;
  for (size_t i = 0; i < n; i += std::max<size_t>(1, stride)) queries.push_back(i);
  // A column grid searched on all cores (NearestOther): FLANN's k-d tree
  // was built on one, 14 % of the CPU time of Herz-Jesu-P8's merge and write.
  const std::vector<int32_t> nearest = NearestOther(xyz, queries);
  for (size_t q = 0; q < queries.size(); ++q) {
    sum.sum += (cloud.points[queries[q]].position - cloud.points[nearest[q]].position).norm();
  }
  sum.samples = static_cast<long>(queries.size());
  return sum;
}

double MeanPointSpacing(const PointCloud& cloud, size_t max_samples) {
  const size_t n = cloud.points.size();
  if (n < 2) return 0;
  const SpacingSum s =
      SumPointSpacing(cloud, std::max<size_t>(1, n / std::max<size_t>(1, max_samples)));
  return s.sum / static_cast<double>(s.samples);
}

namespace {

struct Extent {
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin;
  double xmax = -xmin, ymax = -xmin;
};

Extent CloudExtent(const PointCloud& cloud) {
  Extent e;
  for (const CloudPoint& p : cloud.points) {
    e.xmin = std::min(e.xmin, p.position.x());
    e.xmax = std::max(e.xmax, p.position.x());
    e.ymin = std::min(e.ymin, p.position.y());
    e.ymax = std::max(e.ymax, p.position.y());
  }
  return e;
}

}  // namespace

CloudFootprint MeasureFootprint(const PointCloud& cloud, double cell_size) {
  if (!(std::isfinite(cell_size) && cell_size > 0)) {
    throw Error("footprint: expected a cell size > 0 (cell_size = " + std::to_string(cell_size) +
                ")");
  }
  CloudFootprint f;
  f.cell_size = cell_size;
  if (cloud.points.empty()) return f;
  const Eigen::Vector3d o = cloud.points.front().position;
  std::unordered_map<unsigned long long, char> cells;
  for (const CloudPoint& p : cloud.points) {
    const long long cx = static_cast<long long>(std::floor((p.position.x() - o.x()) / cell_size));
    const long long cy = static_cast<long long>(std::floor((p.position.y() - o.y()) / cell_size));
    // Unsigned: a cell west of the first point has cx < 0, and shifting a
    // negative value is undefined (UBSan, TiledMergeTest).
    cells[(static_cast<unsigned long long>(cx) << 32) ^
          (static_cast<unsigned long long>(cy) & 0xffffffffULL)] = 1;
  }
  f.occupied_cells = static_cast<long>(cells.size());
  f.area = static_cast<double>(f.occupied_cells) * cell_size * cell_size;
  f.density = static_cast<double>(cloud.points.size()) / f.area;
  return f;
}

double DsmCellSize(const DsmOptions& options, double mean_spacing) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("dsm: expected " + problem);
  const double cell = options.cell_size == 0 ? 2 * mean_spacing : options.cell_size;
  if (!(cell > 0)) throw Error("dsm: the points coincide; give a cell size (--dsm-cell)");
  return cell;
}

GeoRaster EmptyDsm(double xmin, double ymin, double xmax, double ymax, double cell,
                   const std::string& crs) {
  GeoRaster r;
  // Whole cells from a multiple of the cell size, so that rasters of
  // neighbouring runs line up.
  r.origin_x = std::floor(xmin / cell) * cell;
  r.origin_y = std::ceil(ymax / cell) * cell;
  if (r.origin_y == ymax) r.origin_y += cell;
  const double w = std::floor((xmax - r.origin_x) / cell) + 1;
  const double h = std::floor((r.origin_y - ymin) / cell) + 1;
  if (w * h > static_cast<double>(1 << 28)) {
    std::ostringstream s;
    s << "dsm: a cell of " << cell << " gives " << w << " x " << h
      << " cells; expected at most 2^28 (give a larger --dsm-cell)";
    throw Error(s.str());
  }
  r.width = static_cast<int>(w);
  r.height = static_cast<int>(h);
  r.cell_size = cell;
  r.crs = crs;
  r.values.assign(static_cast<size_t>(r.width) * r.height, std::numeric_limits<float>::quiet_NaN());
  return r;
}

size_t RasterCellIndex(const GeoRaster& r, double x, double y) {
  const int c = std::clamp(static_cast<int>((x - r.origin_x) / r.cell_size), 0, r.width - 1);
  const int row = std::clamp(static_cast<int>((r.origin_y - y) / r.cell_size), 0, r.height - 1);
  return static_cast<size_t>(row) * r.width + c;
}

float MedianHeight(std::vector<float>* heights) {
  auto& v = *heights;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

void FillDsmGaps(GeoRaster* dsm, int passes) {
  GeoRaster& r = *dsm;
  for (int pass = 0; pass < passes; ++pass) {
    std::vector<float> next = r.values;
    for (int row = 0; row < r.height; ++row) {
      for (int c = 0; c < r.width; ++c) {
        if (!std::isnan(r.at(c, row))) continue;
        double sum = 0;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int cc = c + dx, rr = row + dy;
            if ((dx == 0 && dy == 0) || cc < 0 || rr < 0 || cc >= r.width || rr >= r.height) {
              continue;
            }
            const float v = r.at(cc, rr);
            if (!std::isnan(v)) {
              sum += v;
              ++n;
            }
          }
        }
        if (n >= 5) next[static_cast<size_t>(row) * r.width + c] = static_cast<float>(sum / n);
      }
    }
    r.values.swap(next);
  }
}

GeoRaster RasterizeDsm(const PointCloud& cloud, const DsmOptions& options, double* cell_size_used) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("dsm: expected " + problem);
  if (cloud.points.empty()) throw Error("dsm: the cloud has no points");
  const double cell =
      DsmCellSize(options, options.cell_size == 0 ? MeanPointSpacing(cloud) : options.cell_size);
  const Extent e = CloudExtent(cloud);
  GeoRaster r = EmptyDsm(e.xmin, e.ymin, e.xmax, e.ymax, cell, cloud.crs);
  std::vector<std::vector<float>> heights(r.values.size());
  for (const CloudPoint& p : cloud.points) {
    heights[RasterCellIndex(r, p.position.x(), p.position.y())].push_back(
        static_cast<float>(p.position.z()));
  }
  for (size_t i = 0; i < heights.size(); ++i) {
    if (!heights[i].empty()) r.values[i] = MedianHeight(&heights[i]);
  }
  FillDsmGaps(&r, options.fill_passes);
  if (cell_size_used) *cell_size_used = cell;
  return r;
}

}  // namespace sapmvs

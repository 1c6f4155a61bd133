#include "sapmvs/evaluate/surface_check.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <utility>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Height of the raster cell under (x, y); NaN outside or empty.
double CellHeight(const GeoRaster& r, double x, double y) {
  const int col = static_cast<int>(std::floor((x - r.origin_x) / r.cell_size));
  const int row = static_cast<int>(std::floor((r.origin_y - y) / r.cell_size));
  if (col < 0 || row < 0 || col >= r.width || row >= r.height || r.IsEmpty(col, row))
    return std::nan("");
  return r.at(col, row);
}

// True when the segment from p towards `camera_center` passes below the
// surface before it rises above `top`.
bool Occluded(const GeoRaster& r, const Eigen::Vector3d& p, const Eigen::Vector3d& camera_center,
              double top) {
  const Eigen::Vector3d d = camera_center - p;
  if (!(d.z() > 0)) return true;
  const double horizontal = std::hypot(d.x(), d.y());
  const double t_top = std::min(1.0, (top - p.z()) / d.z());
  const double step = r.cell_size / std::max(horizontal, 1e-9);
  // Start one cell away: the point's own cell (and its walls) do not hide it.
  for (double t = 1.5 * step; t < t_top; t += step) {
    const Eigen::Vector3d q = p + t * d;
    const double h = CellHeight(r, q.x(), q.y());
    if (std::isfinite(h) && h > q.z() + r.cell_size) return true;
  }
  return false;
}

// Images of `block` that see every point of `points` (in front, inside the
// image, not hidden by the surface), counted up to `need`.
int ViewsSeeingAll(const GeoRaster& surface, const std::vector<Eigen::Vector3d>& points,
                   const Block& block, double top, int need) {
  int views = 0;
  for (const BlockImage& im : block.images) {
    const Camera& cam = im.camera;
    bool all = true;
    for (const Eigen::Vector3d& p : points) {
      if (!(cam.Depth(p) > 0) || !cam.InImage(cam.ProjectDistorted(p)) ||
          Occluded(surface, p, cam.center(), top)) {
        all = false;
        break;
      }
    }
    if (all && ++views >= need) break;
  }
  return views;
}

// Highest height of the surface.
double SurfaceTop(const GeoRaster& surface) {
  double top = -1e300;
  for (size_t i = 0; i < surface.values.size(); ++i) {
    if (std::isfinite(surface.values[i]) && surface.values[i] != surface.nodata) {
      top = std::max(top, static_cast<double>(surface.values[i]));
    }
  }
  return top;
}

// The check's cells over the surface: options.cell_size squares from the
// surface's top-left corner, as many as fit.
struct CheckGrid {
  int cols = 0, rows = 0;
  double x0 = 0, y0 = 0, cell = 0;
  CheckGrid(const GeoRaster& surface, double cell_size)
      : cols(static_cast<int>(std::floor(surface.width * surface.cell_size / cell_size))),
        rows(static_cast<int>(std::floor(surface.height * surface.cell_size / cell_size))),
        x0(surface.origin_x),
        y0(surface.origin_y),
        cell(cell_size) {}
  double X(int c) const { return x0 + (c + 0.5) * cell; }
  double Y(int r) const { return y0 - (r + 0.5) * cell; }
  // Index of the cell under (x, y); -1 outside the grid.
  long Index(double x, double y) const {
    const int c = static_cast<int>(std::floor((x - x0) / cell));
    const int r = static_cast<int>(std::floor((y0 - y) / cell));
    if (c < 0 || r < 0 || c >= cols || r >= rows) return -1;
    return static_cast<long>(r) * cols + c;
  }
};

// Height of the surface at (x, y) when a cell centred there counts: inside
// options.region (if set) and over a non-empty surface cell; NaN otherwise.
double CountedHeight(const GeoRaster& surface, const SurfaceCheckOptions& options, double x,
                     double y) {
  if (options.region && !options.region(x, y)) return std::nan("");
  return CellHeight(surface, x, y);
}

// LAS class of the cell under (x, y) of a raster on the surface's grid; -1
// without one or outside.
int CellClass(const GeoRaster* classes, double x, double y) {
  if (!classes) return -1;
  const double v = CellHeight(*classes, x, y);
  return std::isfinite(v) ? static_cast<int>(std::lround(v)) : -1;
}

bool Unmatchable(const SurfaceCheckOptions& options, int k) {
  const auto& skip = options.unmatchable_classes;
  return std::find(skip.begin(), skip.end(), k) != skip.end();
}

// Throws Error for non-positive tolerance or cell size, or a class raster
// not on the surface's grid.
void ValidateOptions(const GeoRaster& surface, const SurfaceCheckOptions& options) {
  if (!(options.tolerance > 0) || !(options.cell_size > 0)) {
    throw Error("surface check: tolerance and cell size must be > 0");
  }
  if (const GeoRaster* k = options.classes) {
    if (k->width != surface.width || k->height != surface.height ||
        std::abs(k->origin_x - surface.origin_x) > 1e-6 * surface.cell_size ||
        std::abs(k->origin_y - surface.origin_y) > 1e-6 * surface.cell_size ||
        std::abs(k->cell_size - surface.cell_size) > 1e-9 * surface.cell_size) {
      throw Error("surface check: the class raster is not on the surface's grid (expected " +
                  std::to_string(surface.width) + " x " + std::to_string(surface.height) +
                  " cells of the same size and origin)");
    }
  }
}

// The check cell centred at (x, y): kNotSeen unless it counts (region,
// surface) and min_images images see its centre, else its class (-1 without
// a class raster).
constexpr int kNotSeen = -2;
int SeenClass(const GeoRaster& surface, const Block& block, const SurfaceCheckOptions& options,
              double top, double x, double y) {
  const double h = CountedHeight(surface, options, x, y);
  if (!std::isfinite(h)) return kNotSeen;
  if (ViewsSeeingAll(surface, {Eigen::Vector3d(x, y, h)}, block, top, options.min_images) <
      options.min_images) {
    return kNotSeen;
  }
  return CellClass(options.classes, x, y);
}

}  // namespace

std::optional<GeoRaster> ReadClassRasterBeside(const std::string& truth_path) {
  const auto path = std::filesystem::path(truth_path).parent_path() / "classes.tif";
  if (!std::filesystem::exists(path)) return std::nullopt;
  return ReadGeoRaster(path);
}

SurfaceCheck CheckAgainstSurface(const PointCloud& cloud, const GeoRaster& surface,
                                 const Block& block, const SurfaceCheckOptions& options) {
  ValidateOptions(surface, options);
  SurfaceCheck out;
  out.points = static_cast<long>(cloud.points.size());
  const CheckGrid grid(surface, options.cell_size);
  std::vector<uint8_t> covered(static_cast<size_t>(grid.cols) * grid.rows, 0);
  std::vector<double> abs_dz;
  for (const CloudPoint& p : cloud.points) {
    if (options.region && !options.region(p.position.x(), p.position.y())) continue;
    const double h = CellHeight(surface, p.position.x(), p.position.y());
    if (!std::isfinite(h)) continue;
    ++out.checked;
    const double dz = std::abs(p.position.z() - h);
    abs_dz.push_back(dz);
    const int k = CellClass(options.classes, p.position.x(), p.position.y());
    if (k >= 0) ++out.by_class[k].checked;
    if (dz > options.tolerance) continue;
    ++out.within;
    if (k >= 0) ++out.by_class[k].within;
    const long cell = grid.Index(p.position.x(), p.position.y());
    if (cell >= 0) covered[static_cast<size_t>(cell)] = 1;
  }
  if (out.checked > 0) {
    out.share_within = static_cast<double>(out.within) / out.checked;
    std::nth_element(abs_dz.begin(), abs_dz.begin() + abs_dz.size() / 2, abs_dz.end());
    out.median_abs_dz = abs_dz[abs_dz.size() / 2];
  }
  const double top = SurfaceTop(surface);
  // Per coverage cell: kNotSeen, or its class.
  std::vector<int> seen_class(covered.size(), kNotSeen);
#pragma omp parallel for schedule(dynamic, 8)
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      seen_class[static_cast<size_t>(r) * grid.cols + c] =
          SeenClass(surface, block, options, top, grid.X(c), grid.Y(r));
    }
  }
  long seen = 0, hit = 0;
  for (size_t i = 0; i < seen_class.size(); ++i) {
    const int k = seen_class[i];
    if (k == kNotSeen) continue;
    if (k >= 0) {
      ClassCheck& cc = out.by_class[k];
      ++cc.cells_seen;
      if (covered[i]) ++cc.cells_covered;
      if (Unmatchable(options, k)) continue;
    }
    ++seen;
    if (covered[i]) ++hit;
  }
  out.cells_seen = seen;
  out.cells_covered = hit;
  out.coverage = seen > 0 ? static_cast<double>(hit) / seen : 0;
  return out;
}

WindowBound WindowCoverageBound(const GeoRaster& surface, const Block& block,
                                const SurfaceCheckOptions& options, double radius) {
  ValidateOptions(surface, options);
  if (!(radius > 0)) throw Error("window bound: radius must be > 0");
  const CheckGrid grid(surface, options.cell_size);
  const double top = SurfaceTop(surface);
  // A window centred at (x, y): its 3 x 3 samples on the surface fit one
  // plane (slopes from opposite samples) and are all seen by min_images
  // images.
  auto window_fits = [&](double x, double y) {
    std::vector<Eigen::Vector3d> q;
    for (int j = -1; j <= 1; ++j) {
      for (int i = -1; i <= 1; ++i) {
        const double h = CellHeight(surface, x + i * radius, y + j * radius);
        if (!std::isfinite(h)) return false;
        q.emplace_back(x + i * radius, y + j * radius, h);
      }
    }
    const double zc = q[4].z();
    const double sx = (q[5].z() - q[3].z()) / (2 * radius);
    const double sy = (q[7].z() - q[1].z()) / (2 * radius);
    for (const Eigen::Vector3d& p : q) {
      if (std::abs(p.z() - (zc + sx * (p.x() - x) + sy * (p.y() - y))) > options.tolerance) {
        return false;
      }
    }
    return ViewsSeeingAll(surface, q, block, top, options.min_images) >= options.min_images;
  };
  long seen = 0, centred = 0, any_window = 0;
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : seen, centred, any_window)
  for (int r = 0; r < grid.rows; ++r) {
    for (int c = 0; c < grid.cols; ++c) {
      const double x = grid.X(c), y = grid.Y(r);
      const int k = SeenClass(surface, block, options, top, x, y);
      if (k == kNotSeen || (k >= 0 && Unmatchable(options, k))) continue;
      ++seen;
      if (window_fits(x, y)) {
        ++centred;
        ++any_window;
        continue;
      }
      bool any = false;
      for (int j = -1; j <= 1 && !any; ++j) {
        for (int i = -1; i <= 1 && !any; ++i) {
          if (i != 0 || j != 0) any = window_fits(x + i * radius, y + j * radius);
        }
      }
      any_window += any;
    }
  }
  WindowBound out;
  out.cells_seen = seen;
  out.centred = centred;
  out.any = any_window;
  return out;
}

double ShareNearSurface(const PointCloud& cloud, const GeoRaster& surface, double radius) {
  if (!(radius > 0)) {
    throw Error("near-surface radius " + std::to_string(radius) + "; expected a positive distance");
  }
  if (cloud.points.empty()) return 0;
  const double cell = surface.cell_size;
  const int reach = static_cast<int>(std::ceil(radius / cell));
  auto height = [&](int c, int r) {
    return c < 0 || r < 0 || c >= surface.width || r >= surface.height || surface.IsEmpty(c, r)
               ? std::numeric_limits<double>::quiet_NaN()
               : static_cast<double>(surface.at(c, r));
  };
  const long n = static_cast<long>(cloud.points.size());
  long near = 0;
#pragma omp parallel for reduction(+ : near) schedule(static)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = cloud.points[i].position;
    const int pc = static_cast<int>(std::floor((p.x() - surface.origin_x) / cell));
    const int pr = static_cast<int>(std::floor((surface.origin_y - p.y()) / cell));
    if (std::isnan(height(pc, pr))) continue;
    bool found = false;
    for (int r = pr - reach; r <= pr + reach && !found; ++r) {
      for (int c = pc - reach; c <= pc + reach && !found; ++c) {
        const double top = height(c, r);
        if (std::isnan(top)) continue;
        double bottom = top;
        for (const auto& [dc, dr] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const double z = height(c + dc, r + dr);
          if (!std::isnan(z)) bottom = std::min(bottom, z);
        }
        // Horizontal distance to the cell's square, vertical to its column.
        const Eigen::Vector2d centre = surface.CellCenter(c, r);
        const double dx = std::max(0.0, std::abs(p.x() - centre.x()) - 0.5 * cell);
        const double dy = std::max(0.0, std::abs(p.y() - centre.y()) - 0.5 * cell);
        const double dz = p.z() > top ? p.z() - top : (p.z() < bottom ? bottom - p.z() : 0.0);
        found = dx * dx + dy * dy + dz * dz <= radius * radius;
      }
    }
    near += found;
  }
  return static_cast<double>(near) / static_cast<double>(n);
}

}  // namespace sapmvs

#include "sapmvs/block/dem.h"

#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "util/input_file.h"

namespace sapmvs {
namespace {}

Dem Dem::Load(const std::filesystem::path& path) {
  RequireRegularFile(path);
  GDALAllRegister();
  // GTiff decodes the blocks of one RasterIO call on all cores (GDAL >= 3.6;
  // other drivers and older versions ignore it, and a config option, unlike
  // an open option, warns for none): a simulated block's DEM is its 0.11 m
  // truth, 23 M deflated cells, 0.5 s of every run on one core. A user's own
  // GDAL_NUM_THREADS (environment or config) is left to rule.
  const bool set_threads = CPLGetConfigOption("GDAL_NUM_THREADS", nullptr) == nullptr;
  if (set_threads) CPLSetThreadLocalConfigOption("GDAL_NUM_THREADS", "ALL_CPUS");
  struct ResetThreads {
    bool set;
    ~ResetThreads() {
      if (set) CPLSetThreadLocalConfigOption("GDAL_NUM_THREADS", nullptr);
    }
  } reset_threads{set_threads};
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) throw Error(path.string() + ": cannot read elevation raster");
  Dem dem;
  dem.width_ = ds->GetRasterXSize();
  dem.height_ = ds->GetRasterYSize();
  if (ds->GetGeoTransform(dem.geo_) != CE_None) {
    throw Error(path.string() + ": elevation raster has no geotransform");
  }
  if (dem.geo_[2] != 0 || dem.geo_[4] != 0) {
    throw Error(path.string() + ": rotated rasters are not supported (expected north-up)");
  }
  GDALRasterBand* band = ds->GetRasterBand(1);
  dem.z_.resize(static_cast<size_t>(dem.width_) * dem.height_);
  // A row of blocks at a time, each dropped from GDAL's block cache once
  // copied: read whole, a fine DEM sat in memory twice, the run's peak.
  int block_w = 0, block_h = 0;
  band->GetBlockSize(&block_w, &block_h);
  const int rows = std::max(1, block_h);
  for (int y = 0; y < dem.height_; y += rows) {
    const int n = std::min(rows, dem.height_ - y);
    if (band->RasterIO(GF_Read, 0, y, dem.width_, n,
                       dem.z_.data() + static_cast<size_t>(y) * dem.width_, dem.width_, n,
                       GDT_Float32, 0, 0) != CE_None) {
      throw Error(path.string() + ": cannot read elevation values");
    }
    band->FlushCache();
  }
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  for (float& z : dem.z_) {
    if (!std::isfinite(z) || (has_nodata && z == static_cast<float>(nodata))) {
      z = std::numeric_limits<float>::quiet_NaN();
    }
  }
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  for (float z : dem.z_) {
    if (std::isfinite(z)) {
      zmin = std::min(zmin, static_cast<double>(z));
      zmax = std::max(zmax, static_cast<double>(z));
    }
  }
  if (std::isfinite(zmax)) {
    dem.zmin_ = zmin;
    dem.zmax_ = zmax;
  }
  return dem;
}

double Dem::Height(double x, double y) const {
  // Cell centres sit at half-integer raster coordinates.
  const double col = (x - geo_[0]) / geo_[1] - 0.5;
  const double row = (y - geo_[3]) / geo_[5] - 0.5;
  if (!(col >= 0 && row >= 0 && col <= width_ - 1 && row <= height_ - 1)) return kNaN;
  const int c0 = std::min(static_cast<int>(col), std::max(width_ - 2, 0));
  const int r0 = std::min(static_cast<int>(row), std::max(height_ - 2, 0));
  const int c1 = std::min(c0 + 1, width_ - 1), r1 = std::min(r0 + 1, height_ - 1);
  const double fc = col - c0, fr = row - r0;
  auto at = [&](int r, int c) {
    return static_cast<double>(z_[static_cast<size_t>(r) * width_ + c]);
  };
  return (1 - fr) * ((1 - fc) * at(r0, c0) + fc * at(r0, c1)) +
         fr * ((1 - fc) * at(r1, c0) + fc * at(r1, c1));
}

Eigen::Vector3d Dem::Intersect(const Eigen::Vector3d& center, const Eigen::Vector3d& dir) const {
  const Eigen::Vector3d d = dir.normalized();
  if (!(d.z() < 0)) return Eigen::Vector3d::Constant(kNaN);
  // Start where the ray reaches the highest plausible surface, step half a
  // cell (in 3D) and refine the crossing by bisection.
  const double zmin = zmin_, zmax = zmax_;
  if (!std::isfinite(zmax)) return Eigen::Vector3d::Constant(kNaN);
  double t = std::max(0.0, (center.z() - zmax) / -d.z());
  const double step = 0.5 * cell_size();
  const double t_end = (center.z() - zmin) / -d.z() + step;
  double prev_t = -1;
  for (; t < t_end; t += step) {
    const Eigen::Vector3d p = center + t * d;
    const double h = Height(p.x(), p.y());
    if (std::isnan(h)) {
      if (prev_t >= 0) return Eigen::Vector3d::Constant(kNaN);
      continue;
    }
    if (p.z() <= h) {
      double lo = prev_t >= 0 ? prev_t : t - step, hi = t;
      for (int k = 0; k < 40; ++k) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector3d q = center + mid * d;
        const double hq = Height(q.x(), q.y());
        if (!std::isnan(hq) && q.z() <= hq)
          hi = mid;
        else
          lo = mid;
      }
      return center + hi * d;
    }
    prev_t = t;
  }
  return Eigen::Vector3d::Constant(kNaN);
}

double Dem::MedianHeight() const {
  std::vector<float> v;
  v.reserve(z_.size());
  for (float z : z_) {
    if (std::isfinite(z)) v.push_back(z);
  }
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace sapmvs

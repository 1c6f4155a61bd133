// Dem::Load: GDAL code, in the GDAL module (cli/gdal_module.h).
#include "sapmvs/block/dem.h"

#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "sapmvs/util/error.h"
#include "util/gdal_drivers.h"
#include "util/input_file.h"

namespace sapmvs {

Dem Dem::Load(const std::filesystem::path& path, long max_cells) {
  RequireRegularFile(path);
  RegisterAllGdalDrivers();
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
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  auto valid = [&](float z) {
    return std::isfinite(z) && !(has_nodata && z == static_cast<float>(nodata));
  };
  const int f = std::clamp(
      static_cast<int>(std::ceil(std::sqrt(static_cast<double>(dem.width_) * dem.height_ /
                                           static_cast<double>(std::max(1L, max_cells))) -
                                 1e-9)),
      1, std::max(1, std::min(dem.width_, dem.height_)));
  const int full_width = dem.width_, full_height = dem.height_;
  if (f > 1) {
    dem.width_ = full_width / f;
    dem.height_ = full_height / f;
    dem.geo_[1] *= f;
    dem.geo_[5] *= f;
  }
  dem.z_.assign(static_cast<size_t>(dem.width_) * dem.height_,
                std::numeric_limits<float>::quiet_NaN());
  // A row of blocks at a time (f rows at least), each dropped from GDAL's
  // block cache once copied: read whole, a fine DEM sat in memory twice, the
  // run's peak.
  int block_w = 0, block_h = 0;
  band->GetBlockSize(&block_w, &block_h);
  const int rows = f * std::max(1, (std::max(1, block_h) + f - 1) / f);
  const int used_height = dem.height_ * f;
  std::vector<float> chunk(static_cast<size_t>(full_width) * rows);
  std::vector<double> sum(dem.width_);
  std::vector<int> count(dem.width_);
  for (int y = 0; y < used_height; y += rows) {
    const int n = std::min(rows, used_height - y);
    if (band->RasterIO(GF_Read, 0, y, full_width, n, chunk.data(), full_width, n, GDT_Float32, 0,
                       0) != CE_None) {
      throw Error(path.string() + ": cannot read elevation values");
    }
    band->FlushCache();
    for (int r = 0; r < n; r += f) {
      std::fill(sum.begin(), sum.end(), 0.0);
      std::fill(count.begin(), count.end(), 0);
      for (int dr = 0; dr < f; ++dr) {
        const float* row = chunk.data() + static_cast<size_t>(r + dr) * full_width;
        for (int x = 0; x < dem.width_ * f; ++x) {
          if (!valid(row[x])) continue;
          sum[x / f] += row[x];
          ++count[x / f];
        }
      }
      float* out = dem.z_.data() + static_cast<size_t>((y + r) / f) * dem.width_;
      for (int x = 0; x < dem.width_; ++x)
        if (count[x] > 0) out[x] = static_cast<float>(sum[x] / count[x]);
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

}  // namespace sapmvs

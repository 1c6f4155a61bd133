// Dem::Load: GDAL code, in the GDAL module (cli/gdal_module.h).
#include "sapmvs/block/dem.h"

#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "sapmvs/util/error.h"
#include "util/gdal_drivers.h"
#include "util/input_file.h"

namespace sapmvs {

Dem Dem::Load(const std::filesystem::path& path) {
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

}  // namespace sapmvs

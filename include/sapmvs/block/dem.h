#pragma once
// An elevation raster (DEM/DSM) read with GDAL, in the block's frame, with
// bilinear lookup and ray intersection.

#include <Eigen/Core>
#include <filesystem>
#include <limits>
#include <vector>

namespace sapmvs {

class Dem {
 public:
  // The most cells Load keeps: the plan finds each image's ground with one
  // ray, at the scale of its footprint, not of a DEM that may be the
  // simulator's truth at a fraction of the GSD (the 60-image 12 MP flight's:
  // 190 M cells, 760 MB, which the plan's peak held twice).
  static constexpr long kMaxCells = 1L << 24;
  // Reads band 1 of `path`, a raster of more than max_cells cells as the
  // mean of the valid ones of f x f of its cells (the least f that fits,
  // the last f - 1 rows and columns at most left out); throws naming the
  // file when it is not a north-up raster GDAL can read.
  static Dem Load(const std::filesystem::path& path, long max_cells = kMaxCells);

  // Bilinear height at world (x, y) between cell centres; NaN outside the
  // raster or where a corner is nodata.
  double Height(double x, double y) const;
  // First intersection of the ray center + t dir (t > 0) with the surface,
  // marched at half a cell; nullopt-like NaN vector when it misses.
  Eigen::Vector3d Intersect(const Eigen::Vector3d& center, const Eigen::Vector3d& dir) const;
  // Median of the valid heights.
  double MedianHeight() const;

  int width() const { return width_; }
  int height() const { return height_; }
  double cell_size() const { return std::abs(geo_[1]); }

 private:
  int width_ = 0, height_ = 0;
  double geo_[6] = {0, 1, 0, 0, 0, -1};  // GDAL geotransform
  std::vector<float> z_;                 // row-major, NaN = nodata
  // The lowest and highest height, found once at Load: Intersect bounds its
  // march by them, and scanning the raster per ray made a block's footprints
  // cost images x cells (1,000 images on a 5,000 x 3,400 DEM: minutes).
  double zmin_ = std::numeric_limits<double>::quiet_NaN(), zmax_ = zmin_;
};

}  // namespace sapmvs

#pragma once
// What a merged cloud is turned into for users: a DSM raster (GeoTIFF; its
// pictures are dsm_picture.h's), and the paper's cloud statistics (Tables 4, 6
// and 8: average distance between points, density).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/option_spec.h"

namespace sapmvs {

struct DsmOptions {
  // Cell side, CRS units; 0 = twice the mean point spacing, so that most
  // cells hold a few points and the median is meaningful.
  double cell_size = 0;
  // Passes of gap filling: an empty cell with at least 5 of its 8 neighbours
  // filled takes their mean. Each pass closes gaps about 2 cells wide; wider
  // holes stay nodata rather than be invented. 0 to 10.
  int fill_passes = 1;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
};

template <class F>
void VisitFields(DsmOptions& o, F&& f) {
  f(Field(o.cell_size, "cell_size")
        .Flag("--dsm-cell")
        .In("Merge and DSM")
        .Unit("CRS units")
        .Range(AtLeast(0))
        .Help("DSM cell, CRS units (0 = twice the mean point spacing)"));
  f(Field(o.fill_passes, "fill_passes")
        .Flag("--dsm-fill")
        .In("Merge and DSM")
        .Range(Between(0, 10))
        .Help("DSM gap-filling passes"));
}

// Mean distance from a point to its nearest neighbour (3D), CRS units; over
// at most `max_samples` points taken at an even stride (the statistic is
// stable long before a million). 0 for fewer than 2 points.
double MeanPointSpacing(const PointCloud& cloud, size_t max_samples = 200000);

// MeanPointSpacing's parts, for a cloud seen in tiles (tiled_merge.h): the
// summed distances from every `stride`-th point (from the first) to its
// nearest neighbour, and how many.
struct SpacingSum {
  double sum = 0;
  long samples = 0;
};
SpacingSum SumPointSpacing(const PointCloud& cloud, size_t stride);

struct CloudFootprint {
  double cell_size = 0;     // of the occupancy grid, CRS units
  long occupied_cells = 0;  // cells holding at least one point
  double area = 0;          // occupied_cells * cell_size^2, CRS units squared
  double density = 0;       // points per unit area of that footprint
};
// The ground the cloud covers, on a grid of `cell_size` (> 0).
CloudFootprint MeasureFootprint(const PointCloud& cloud, double cell_size);

// Median height per cell over the cloud's XY extent, north up, NaN nodata,
// the cloud's CRS. Throws sapmvs::Error for bad options, an empty cloud or a
// raster over 2^28 cells (a cell size far too small for the extent).
GeoRaster RasterizeDsm(const PointCloud& cloud, const DsmOptions& options,
                       double* cell_size_used = nullptr);

// RasterizeDsm's steps, for a cloud seen in chunks (streamed_dsm.h).
// The cell side: options.cell_size, or twice `mean_spacing` for 0. Throws
// sapmvs::Error for bad options or a cell of 0.
double DsmCellSize(const DsmOptions& options, double mean_spacing);
// The all-nodata raster covering the points' XY extent. Throws sapmvs::Error
// beyond 2^28 cells.
GeoRaster EmptyDsm(double xmin, double ymin, double xmax, double ymax, double cell,
                   const std::string& crs);
// The index into `dsm.values` of the cell holding (x, y), clamped to the raster.
size_t RasterCellIndex(const GeoRaster& dsm, double x, double y);
// The median of a cell's heights (reorders them; not empty).
float MedianHeight(std::vector<float>* heights);
// `passes` passes of gap filling (DsmOptions::fill_passes).
void FillDsmGaps(GeoRaster* dsm, int passes);

}  // namespace sapmvs

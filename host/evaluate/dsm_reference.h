#pragma once
// Reference heights and completeness from a DSM raster.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/evaluate/dsm_completeness.h"
#include "sapmvs/io/raster_io.h"

namespace sapmvs {

// The DSM at world (x, y), interpolated bilinearly between cell centres, so
// that it is the stored value exactly at a centre and the mean of four cells
// at their common corner. Between the outermost centres and the raster's
// edge the edge value is held. NaN outside the raster or when a cell that
// carries weight is empty.
double DsmHeight(const GeoRaster& dsm, double x, double y);

// The cell holding world (x, y) (a point on a cell edge goes to the cell east
// or south of it), or -1 outside the raster: the row-major index.
long DsmCellIndex(const GeoRaster& dsm, double x, double y);

// Non-empty cells whose centre lies in [xmin, xmax] x [ymin, ymax].
DsmFootprint FootprintFromBox(const GeoRaster& dsm, double xmin, double ymin, double xmax,
                              double ymax);

// Non-empty cells whose centre, at the DSM height, projects into at least
// `min_images` images of `block` (pinhole projection into the undistorted
// image, as the matcher sees it).
DsmFootprint FootprintFromBlock(const GeoRaster& dsm, const Block& block, int min_images = 2);

// The share of the footprint's cells that hold a point of `points` with
// |dz| <= tolerance (dz NaN = no reference).
Completeness ComputeCompleteness(const GeoRaster& dsm, const DsmFootprint& footprint,
                                 const std::vector<Eigen::Vector3d>& points,
                                 const std::vector<double>& dz, double tolerance);

}  // namespace sapmvs

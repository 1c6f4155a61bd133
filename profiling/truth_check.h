#pragma once
// The profiling tools' check of a cloud against the simulator's truth
// (truth/dsm.tif, and classes.tif beside it), shared so that compare_modes,
// end_to_end and versus_pmvs2 report the same numbers for the same cloud:
// accuracy within one full-resolution GSD, coverage on cells of `csize`
// pixels of the matched level (the spacing a matcher emits points at).
#include <filesystem>
#include <optional>

#include "sapmvs/block/block.h"
#include "sapmvs/evaluate/surface_check.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"

namespace sapmvs {

struct Truth {
  GeoRaster surface;
  std::optional<GeoRaster> classes;  // with it, water is not asked to be covered
};

Truth ReadTruth(const std::filesystem::path& dsm);

// `gsd` is the block's median full-resolution GSD; cells are `cell_pixels`
// working pixels of `level` on a side. The options point into `truth`.
SurfaceCheckOptions TruthCheckOptions(const Truth& truth, double gsd, int level,
                                      double cell_pixels = 2);

// `block` must be in the truth's (world) frame.
SurfaceCheck CheckAgainstTruth(const PointCloud& cloud, const Truth& truth, const Block& block,
                               double gsd, int level, double cell_pixels = 2);

}  // namespace sapmvs

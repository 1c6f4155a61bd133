#pragma once
// Accuracy and coverage of a cloud against a true surface raster (the
// simulator's truth/dsm.tif): the acceptance measure of the matcher.
//  - accuracy: the share of points within `tolerance` of the surface,
//    vertically, the surface read at the cell under the point (the truth DSM
//    is flat-topped cells, so no interpolation across walls);
//  - coverage: the ground is cut into cells of `cell_size`; a cell is "seen"
//    when the surface at its centre projects into at least `min_images`
//    images unoccluded (a ray march through the raster), and "covered" when
//    it holds a point within `tolerance`;
//  - with a class raster (the simulator's truth/classes.tif, LAS codes), both
//    split by class, and cells of an unmatchable class (water: no texture to
//    match) are not counted as seen.
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"

namespace sapmvs {

struct SurfaceCheckOptions {
  double tolerance = 0;  // block units, > 0 (e.g. one GSD)
  double cell_size = 0;  // block units, > 0 (e.g. the matcher's cell footprint)
  int min_images = 3;
  // When set, only points and cells (by their centre) at world (x, y) where
  // it returns true count: to compare zones of one cloud, such as group
  // borders and group centres. Called concurrently.
  std::function<bool(double x, double y)> region;
  // LAS class per cell on the surface's grid (same size and origin), or null.
  const GeoRaster* classes = nullptr;
  // Classes whose cells are never "seen": a matcher cannot be asked to cover
  // them (LAS 9, water: flat colour the simulator gives no texture).
  std::vector<int> unmatchable_classes = {9};
};

// The counts of SurfaceCheck for the points and cells of one class.
struct ClassCheck {
  long checked = 0, within = 0;
  long cells_seen = 0, cells_covered = 0;
};

struct SurfaceCheck {
  long points = 0;
  long checked = 0;  // points over a non-empty surface cell
  long within = 0;
  double share_within = 0;  // within / checked
  double median_abs_dz = 0;
  long cells_seen = 0;
  long cells_covered = 0;
  double coverage = 0;  // covered / seen
  // By LAS class, when SurfaceCheckOptions::classes is set; cells of an
  // unmatchable class count their would-be seen cells here (not above).
  std::map<int, ClassCheck> by_class;
};

// The simulator's class raster, classes.tif in the folder of `truth_path`
// (its truth/dsm.tif), when there is one.
std::optional<GeoRaster> ReadClassRasterBeside(const std::string& truth_path);

// What a window matcher could cover at all, on CheckAgainstSurface's cells:
// of the cells seen in min_images images (unmatchable classes left out), those
// with a square window of half-width `radius` on the true surface, centred
// on the cell (`centred`) or on the cell shifted by `radius` along x, y or
// both (`any`), whose 3 x 3 samples fit one plane within `tolerance` and are
// all seen by the same min_images images. A matcher that keeps only its
// windows' centres (PMVS, with check cells of one matcher cell) covers about
// `centred` at most (its centres may sit anywhere in the cell, not only at
// the cell's centre); one that keeps whole windows (SAPMVS) about `any` (up
// to the 3 x 3 sampling).
struct WindowBound {
  long cells_seen = 0;
  long centred = 0;
  long any = 0;
};
// Throws Error for non-positive tolerance, cell size or radius, or a class
// raster not on the surface's grid.
WindowBound WindowCoverageBound(const GeoRaster& surface, const Block& block,
                                const SurfaceCheckOptions& options, double radius);

// Share of `cloud`'s points within `radius` (3D) of `surface`, its cells
// taken as columns: each cell's top spans the cell, and its sides reach down
// to its lowest 4-neighbour, so that walls count as surface. What any
// accurate cloud can cover of another cloud at `radius`: the benchmark's
// ceiling for the share of PMVS2's points with one of ours near them.
// Points over empty cells or off the raster count as not near. Throws Error
// for a non-positive radius.
double ShareNearSurface(const PointCloud& cloud, const GeoRaster& surface, double radius);

// Throws Error for non-positive tolerance or cell size, or a class raster
// not on the surface's grid.
SurfaceCheck CheckAgainstSurface(const PointCloud& cloud, const GeoRaster& surface,
                                 const Block& block, const SurfaceCheckOptions& options);

}  // namespace sapmvs

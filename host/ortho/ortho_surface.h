#pragma once
// The DSM as the orthophoto uses it: a height for every ortho cell, the
// objects (buildings, trees) that must each come from one image, and the
// part of the grid an image can see.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sapmvs/block/camera.h"
#include "sapmvs/io/raster_io.h"

namespace sapmvs {

// A rectangle of cells, [col0, col1) x [row0, row1).
struct CellWindow {
  int col0 = 0, row0 = 0, col1 = 0, row1 = 0;
  bool Empty() const { return col1 <= col0 || row1 <= row0; }
};

struct OrthoSurface {
  // The DSM with its holes filled (FillEnclosedHoles).
  GeoRaster dsm;
  // The ortho's cells; values are the heights, NaN where the DSM has none.
  GeoRaster grid;
  // Per DSM cell: the object it belongs to, -1 for open ground.
  std::vector<int> dsm_object;
  int objects = 0;
  // The DSM cell under each ortho column and row.
  std::vector<int> dsm_col, dsm_row;
  double zmin = 0, zmax = 0;  // the DSM's height range
  // WallQuads of `dsm`: where the depth buffers draw walls.
  std::vector<uint8_t> walls;

  int ObjectAt(int col, int row) const {
    return dsm_object[static_cast<size_t>(dsm_row[row]) * dsm.width + dsm_col[col]];
  }
};

// Per quad of `dsm` (cells (c, r) to (c + 1, r + 1), at r * width + c): 1
// where the heights of its valid cells span more than `step`, a wall that
// the depth buffers draw as blocks (OrthoDepthBuffer), else 0.
std::vector<uint8_t> WallQuads(const GeoRaster& dsm, double step);

// Fills each hole of `dsm` that the valid cells enclose with a low height
// of its rim (the 10th percentile): such holes are mostly ground that few
// images see, beside walls and under trees, or water, which matches no
// texture; the ortho still needs a surface there to take colours from, and
// visibility then picks the images that see it. The hole's cells within 1.5
// cells of its rim take the nearest rim cell's height instead: a roof's
// edge that matched no points stays the roof's. Returns the cells filled.
long FillEnclosedHoles(GeoRaster* dsm);

// `dsm` with its enclosed holes filled (FillEnclosedHoles), then heights
// interpolated bilinearly between the centres of the DSM's valid
// cells (where some of the four are empty, from those that are not). A DSM
// cell is steep when its height differs from a 4-neighbour's by more than
// `object_slope` times the cell side; the steep cells grown by `margin`
// (CRS units) and joined 8-connected are the objects. Throws sapmvs::Error
// for an ortho over 2^28 cells.
OrthoSurface MakeOrthoSurface(const GeoRaster& dsm, double cell, double object_slope,
                              double margin);

// The cells of `grid` that `camera` can see: its image corners' rays met with
// the planes at heights `zmin` and `zmax`; the whole grid where a corner's
// ray does not come down to them (an oblique view of the horizon).
CellWindow ImageWindow(const Camera& camera, const GeoRaster& grid, double zmin, double zmax);

}  // namespace sapmvs

#pragma once
// The true orthophoto: the block's images draped over its DSM, every cell
// coloured from an image that sees it, so that roofs sit on their
// footprints and the ground behind a building comes from an image that sees
// past it (a plain orthophoto on a terrain model would lean every roof away
// from the image centre and repeat it over the ground it hides).
//
// For each cell, the image that sees it most directly (its ray nearest the
// vertical) among those that see it at all: visibility is decided against
// the DSM drawn into each image's depth buffer (ortho_depth_buffer.h).
// Objects (steep DSM cells, ortho_surface.h) are each taken, wherever it
// sees them, from the image that looks most directly at their centre, so
// that the seams where the chosen image changes run over open ground;
// across a seam the colours are blended over a few cells. Narrow gaps no
// image sees are inpainted from around them; wider ones, and cells without a
// DSM height, stay empty (alpha 0).

#include <cstdint>
#include <functional>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/ortho/ortho_options.h"

namespace sapmvs {

class LevelImageStore;

struct TrueOrtho {
  // The ortho's cells: size, geotransform and CRS (its values are unused).
  GeoRaster grid;
  // 8-bit RGBA per cell, row-major, row 0 north; alpha 0 = empty.
  std::vector<uint8_t> rgba;
  long filled_cells = 0;
  long inpainted_cells = 0;  // of those, gaps no image sees, filled from around
  int images_used = 0;       // images that coloured at least one cell
  int objects = 0;           // objects taken whole from one image
};

// The ortho of `block` at pyramid `level` over `dsm` (block CRS, world
// coordinates, the cameras' frame), on cells of options.cell_size, or of
// `default_cell` for 0. `progress(done, total)` is called as each image's
// colours are taken. `levels`: the run's images at `level` (level_images.h),
// read from there where the matching kept them; else each is decoded.
// Throws sapmvs::Error for bad options, an ortho over 2^28 cells, or an
// image that cannot be read (naming its file).
TrueOrtho MakeTrueOrtho(const Block& block, const GeoRaster& dsm, int level,
                        const OrthoOptions& options, double default_cell,
                        const std::function<void(int, int)>& progress = {},
                        const LevelImageStore* levels = nullptr);

}  // namespace sapmvs

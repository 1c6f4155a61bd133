#pragma once
// The true orthophoto of a scene (truth/ortho.tif): what a camera looking
// straight down from far away records of the cell tops, so that an
// orthophoto made from the images can be checked for colour, position and
// for roofs drawn onto the ground beside them. Walls are never seen.

#include <cstdint>
#include <vector>

#include "sapmvs/io/raster_io.h"
#include "sapmvs/simulate/sim_scene.h"

namespace sapmvs::sim {

struct TrueOrtho {
  // Local scene coordinates (origin_y = the scene's north edge); `values`
  // is left empty.
  GeoRaster grid;
  std::vector<uint8_t> rgba;  // 4 per cell, row 0 north; alpha 0 outside the scene
};

// Cells of `cell` metres from the scene's north-west corner, as many as
// cover it (the last row and column may reach past it). Each cell is the
// mean linear shade of TopAt over `supersampling` x `supersampling` points,
// recorded as the images are (EncodeChannel with gain 1) without their
// sensor noise. Alpha is 255 where the cell's centre lies in the scene.
TrueOrtho RenderTrueOrtho(const Scene& scene, double cell, int supersampling);

}  // namespace sapmvs::sim

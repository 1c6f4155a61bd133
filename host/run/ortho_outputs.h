#pragma once
// The orthophoto's files in a run folder: ortho.tif, a Cloud-Optimized
// GeoTIFF in the block's CRS for GIS, and ortho.png with its world file
// (ortho.pgw), small enough to open at once.
#include <filesystem>

#include "sapmvs/ortho/true_ortho.h"

namespace sapmvs {

// The PNG's long side is at most this many pixels (the ortho averaged down
// by a whole factor, so that the world file stays exact).
constexpr int kOrthoPictureMaxSide = 2048;

// Writes the three files atomically. Throws sapmvs::Error naming the file.
void WriteOrthoOutputs(const TrueOrtho& ortho, const std::filesystem::path& out);

}  // namespace sapmvs

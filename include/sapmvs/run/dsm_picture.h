#pragma once
// Pictures of a DSM (cloud_dsm.h) made with GDAL's DEM tools: colour relief
// (`GDALDEMProcessing` "color-relief") shaded by a hillshade ("hillshade";
// sun from the north-west, 45 degrees up), as a GeoTIFF on the DSM's own grid
// for GIS, and as a PNG to look at with a world file and a legend.

#include <filesystem>
#include <string>

#include "sapmvs/io/raster_io.h"

namespace sapmvs {

struct DsmPictureOptions {
  // The PNG's map is enlarged by a whole factor, each cell a square of
  // pixels (nearest), until its short side has at least this many pixels, so
  // that a DSM of 127 x 51 cells is readable. >= 1.
  int min_short_side = 600;
  // ... but never past this many on its long side. >= min_short_side.
  int max_long_side = 8192;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
};

// The files WriteDsmPictures writes.
struct DsmPictures {
  // RGB + alpha GeoTIFF, same grid and CRS as the DSM; nodata transparent.
  std::filesystem::path color_tif;
  // The map (nodata light grey) at the top left, and to its right the legend:
  // a colour bar with heights and their unit, and a scale bar.
  std::filesystem::path png;
  // The PNG's world file (`.pgw` beside it): it places the map part; the
  // legend's pixels fall east of the map.
  std::filesystem::path world_file;
};

// Colours run blue - cyan - green - yellow - orange - red over the 1-99 %
// height range (lower and higher cells take the end colours), so that the
// hue falls steadily with height. Each file is written atomically. Throws
// sapmvs::Error naming the file for a DSM without a valid cell, bad options or
// a GDAL failure.
DsmPictures WriteDsmPictures(const GeoRaster& dsm, const std::filesystem::path& color_tif,
                             const std::filesystem::path& png,
                             const DsmPictureOptions& options = {});

}  // namespace sapmvs

#pragma once
// North-up single-band float rasters (DSMs, DEMs, error maps) in and out of
// GeoTIFF through GDAL, and the CRS conversion the point writers share. The
// functions are GDAL code, in the GDAL module (cli/gdal_module.h).

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace sapmvs {

struct GeoRaster {
  int width = 0, height = 0;
  // Top-left corner of the top-left cell (not its centre), in CRS units.
  double origin_x = 0, origin_y = 0;
  // Square cells; columns run east, rows run south.
  double cell_size = 1;
  // Row-major, width * height; row 0 is the north edge.
  std::vector<float> values;
  // Cells equal to `nodata` are empty; NaN cells are always empty.
  float nodata = std::numeric_limits<float>::quiet_NaN();
  // WKT, "EPSG:n" or a PROJ string when writing; WKT after reading; empty =
  // no CRS.
  std::string crs;

  float& at(int col, int row) { return values[static_cast<size_t>(row) * width + col]; }
  float at(int col, int row) const { return values[static_cast<size_t>(row) * width + col]; }
  bool IsEmpty(int col, int row) const {
    const float v = at(col, row);
    return std::isnan(v) || v == nodata;
  }
  // World (x, y) of the centre of cell (col, row).
  Eigen::Vector2d CellCenter(int col, int row) const {
    return {origin_x + (col + 0.5) * cell_size, origin_y - (row + 0.5) * cell_size};
  }
};

// Writes a float32 Cloud-Optimized GeoTIFF (DEFLATE with the floating-point
// predictor, 256 px tiles, averaged overviews) with the geotransform, nodata
// value and CRS, atomically. Throws
// sapmvs::Error naming `path` and the value at fault (inconsistent size, bad
// cell size, unknown CRS) or the GDAL failure; no file is left behind.
void WriteGeoTiff(const std::filesystem::path& path, const GeoRaster& raster);

// Writes `rgba` (8 bit, 4 per pixel, row-major, row 0 north) as an RGB
// Cloud-Optimized GeoTIFF with an alpha band on `grid`'s size, geotransform and CRS (its values are
// not used), atomically, as WriteGeoTiff does.
void WriteColorGeoTiff(const std::filesystem::path& path, const GeoRaster& grid,
                       const std::vector<uint8_t>& rgba);

// Reads band 1 of any raster GDAL opens, as float. A south-up raster is
// flipped to north-up; rotated or non-square cells are refused. Without a
// nodata value in the file, `nodata` is NaN. Throws sapmvs::InputError naming
// the file and what was expected.
GeoRaster ReadGeoRaster(const std::filesystem::path& path);

// Converts a CRS given as WKT, "EPSG:n" or a PROJ string (no network look-up)
// to OGR's default WKT; "" stays "". Throws sapmvs::Error naming the text.
std::string CrsToWkt(const std::string& crs);
// Whether the outputs that need GDAL (the CRS of cloud.las, the DSM
// rasters) can be written, checked while the caller goes on: a run starts
// it before the block's geometry and waits for it before its plan. The
// binary checks the CRS in a child process (cli/gdal_module.cc; 0.08 s, a
// process start and GDAL's), so that a run whose images need no GDAL loads
// it only for its outputs, after the matching's peak of memory.
class GeoOutputsCheck {
 public:
  // Throws at once in the binary when its GDAL module is missing.
  GeoOutputsCheck(std::string crs, std::string source);
  // Without Wait(), waits for the child and drops its answer.
  ~GeoOutputsCheck();
  GeoOutputsCheck(const GeoOutputsCheck&) = delete;
  GeoOutputsCheck& operator=(const GeoOutputsCheck&) = delete;

  // Throws as CrsToWkt when it would refuse the CRS, after `source: ` (the
  // file that gave it).
  void Wait();

 private:
  std::string crs_;
  std::string source_;
  // Only the binary's variant (host/cli/gdal_module.cc) has a child; the
  // in-process one, linked into the tests, leaves them unused.
  [[maybe_unused]] int child_ = -1;         // the checking process
  [[maybe_unused]] int child_stderr_ = -1;  // the read end of its stderr
};
// The resident memory that loading GDAL to write the outputs will add: 0
// where GDAL is linked in or already loaded, and in the binary, before it
// loads its GDAL module, what GDAL and its libraries held at the end of a
// run on `small` (30 MiB, with the drivers the outputs register), rounded
// up. Plans count it in the process where the groups' images load it
// (GdalBytesToMatch).
double GdalBytesToLoad();

// How a report names a CRS: its EPSG code (0 when it has none that PROJ can
// find without the network) and its name ("WGS 84 / UTM zone 32N").
struct CrsIdentity {
  int epsg = 0;
  std::string name;
};
// `crs` as CrsToWkt takes it, not empty. Throws sapmvs::Error naming the text.
CrsIdentity IdentifyCrs(const std::string& crs);
// What LAS needs to know of a CRS given as WKT: its kind and the EPSG codes
// of its horizontal and vertical parts (0 where none is given). All false and
// 0 for text GDAL cannot read.
struct WktFacts {
  bool projected = false;
  bool geographic = false;
  int horizontal_epsg = 0;
  int vertical_epsg = 0;
};
WktFacts ReadWktFacts(const std::string& wkt);
// The CRS's horizontal unit as an axis label: "m", "ft", "ftUS", "deg" for a
// geographic CRS, another unit's name; "" without a CRS or for one that
// cannot be read.
std::string CrsLinearUnit(const std::string& crs);
// How a length in CrsLinearUnit's `unit` is labelled: the unit, or "local
// frame units" without a CRS; a height also in metres for a geographic CRS.
inline std::string LengthLabel(const std::string& unit) {
  return unit.empty() ? "local frame units" : unit;
}
inline std::string HeightLabel(const std::string& unit) {
  return unit == "deg" ? "m" : LengthLabel(unit);
}

}  // namespace sapmvs

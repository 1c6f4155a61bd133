#pragma once
// Point clouds in and out: ASPRS LAS (binary, what GIS and LiDAR tools
// exchange) and XYZ text (what is easy to inspect and to script).
//
// Coordinates are in the units of the CRS the caller names (metres for a
// projected CRS such as UTM, degrees for a geographic one); nothing here
// transforms coordinates between CRSs.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "sapmvs/io/las_extra_field.h"

namespace sapmvs {

struct PointRecord {
  double x = 0, y = 0, z = 0;
  // 16-bit channels, as LAS stores them. 8-bit image colour c is stored as
  // c * 257, so that 255 maps to full scale 65535 (see ColorTo16 / ColorTo8).
  uint16_t r = 0, g = 0, b = 0;
  uint16_t intensity = 0;
  // 1-based, at most 15 in LAS 1.4 formats (7 in formats 0-5).
  uint8_t return_number = 1, number_of_returns = 1;
  // ASPRS class (0 never classified, 1 unclassified, 2 ground, ...).
  uint8_t classification = 0;
};

inline uint16_t ColorTo16(uint8_t c) { return static_cast<uint16_t>(c * 257); }
inline uint8_t ColorTo8(uint16_t c) { return static_cast<uint8_t>((c + 128u) / 257u); }

// Which LAS a writer produces.
enum class LasVersion {
  // LAS 1.2, point data record format 2 (XYZ, intensity, returns, class, RGB;
  // 26 bytes). Every LAS reader opens it: @loaders.gl/las (deck.gl, kepler.gl)
  // refuses versions above 1.3, and formats 0-3 are all that LAS 1.2 readers
  // know. Format 2 rather than 3: a dense cloud has no GPS time to store.
  // Returns and number of returns at most 7, classes at most 31; the CRS as
  // GeoTIFF keys (LASF_Projection/34735) when it has an EPSG code, and as WKT
  // (2112) always.
  k12,
  // LAS 1.4, point data record format 7 (the same and GPS time, 36 bytes),
  // the CRS as WKT only, as LAS 1.4 asks for formats 6-10.
  k14,
};

// "1.2" or "1.4"; throws sapmvs::Error naming `text` and what is accepted.
LasVersion ParseLasVersion(const std::string& text);
std::string ToString(LasVersion version);

struct LasWriteOptions {
  // The CRS of the coordinates: WKT, "EPSG:n" or a PROJ string; empty = none.
  // Stored as WKT (OGRSpatialReference::SetFromUserInput + exportToWkt).
  std::string crs;
  // Coordinate resolution in CRS units, the same on all axes. 0 chooses per
  // axis: 0.001 units (1e-7 for x and y in a geographic CRS, ~1 cm), made
  // coarser by powers of ten only where the extent would not fit in int32.
  double scale = 0;
  // File creation day of year (1-366) and year in the header; 0 = today (UTC).
  // Synthetic data sets fix them so that the same inputs give the same bytes.
  int creation_day = 0;
  int creation_year = 0;
  LasVersion version = LasVersion::k12;

  // Empty when the options are usable, else one line naming the bad value.
  std::string Problem() const;
  bool Check() const { return Problem().empty(); }
};

// Writes `options.version` (see LasVersion), atomically, with `extras` as
// Extra Bytes after each point's record, in the order given, and their
// descriptors in an Extra Bytes VLR. Per axis, the offset is the rounded
// centre of the data. The header's bounding box is that of the stored
// (quantized) coordinates. LAS 1.4: the WKT bit of the global encoding is set
// and the legacy 32-bit point counts are zero, as LAS 1.4 requires for formats
// 6-10; the 64-bit counts are always filled. LAS 1.2: the 32-bit counts, so at
// most 2^32 - 1 points. Extra Bytes descriptors of floating-point fields carry
// the field's min and max (options bits 1 and 2); those of integer fields
// carry none, since revisions of LAS 1.4 disagree on how an integer field's
// min and max are stored (as double, or widened to 64-bit integers).
// Throws sapmvs::Error naming `path` and the point, field or value at fault
// (a non-finite coordinate, a return number the version cannot hold, a value
// its field's type cannot) before anything is written.
void WriteLas(const std::filesystem::path& path, const std::vector<PointRecord>& points,
              const LasWriteOptions& options = {}, const std::vector<LasExtraField>& extras = {});

// A cloud written as LAS in chunks, for clouds that never lie in memory
// whole (a large block's merge, run/tiled_merge.h). The header holds the
// count, the extent and the quantization chosen from it, and the Extra Bytes
// descriptors the ranges of the float fields, so the points are seen twice:
// once to fill a LasCounts and the ranges, once to write them. WriteLas is
// both passes over one vector, so the two give the same bytes.
struct LasCounts {
  size_t count = 0;
  std::array<double, 3> lo{{kInf, kInf, kInf}}, hi{{-kInf, -kInf, -kInf}};  // x y z as given
  std::array<uint64_t, 15> by_return{};  // points by return number 1-15
  // Counts `p` as point number `count`. Throws sapmvs::Error naming `path`
  // and the point for what `version` cannot store (a non-finite coordinate,
  // a return number or class too large).
  void Add(const std::filesystem::path& path, const PointRecord& p, LasVersion version);

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
};

// Adds `chunk` (extra fields of `points` points) to `ranges`: the same fields
// with each one's values reduced to its least and greatest so far, all that
// their descriptors record. Throws sapmvs::Error naming `path` and the value
// when a value does not fit its type.
void WidenExtraRanges(const std::filesystem::path& path, const std::vector<LasExtraField>& chunk,
                      size_t points, std::vector<LasExtraField>* ranges);

// Points the caller holds until the next call, with one value per point in
// each of the extra fields (those of the ranges, in their order); false at
// the end.
using NextLasPoints = std::function<bool(const std::vector<PointRecord>** points,
                                         const std::vector<LasExtraField>** extras)>;

// Writes the points `next` gives as WriteLas does, atomically, from the
// first pass's counts and extra-field ranges. Throws sapmvs::Error naming
// `path` for bad options, more points than LAS 1.2 can count, points that are
// not `counts.count`, or a failed write; nothing is left then.
void WriteLasStream(const std::filesystem::path& path, const LasCounts& counts,
                    const LasWriteOptions& options, const std::vector<LasExtraField>& ranges,
                    const NextLasPoints& next);

struct LasCloud {
  std::vector<PointRecord> points;
  int version_major = 1, version_minor = 4;
  int point_format = 7;
  bool has_rgb = false;  // formats 2, 3, 5, 7, 8, 10; else r g b are 0
  std::array<double, 3> scale{}, offset{};
  std::string crs_wkt;  // from a WKT VLR or EVLR; empty when there is none
  // The fields of an Extra Bytes VLR, in record order; `values` (scale and
  // offset applied) only when ReadLas was asked for them.
  std::vector<LasExtraField> extras;
};

// Reads LAS 1.0-1.4, uncompressed, point formats 0-10. Classification of
// formats 0-5 is the low 5 bits (the class, without the synthetic/key-point/
// withheld flags). Extra Bytes described by an Extra Bytes VLR (LASF_Spec/4)
// are listed in `extras`, and their values read when `extra_values` (a LiDAR
// reference does not need them, and they can cost more memory than the
// points); undescribed extra bytes are skipped. A descriptor of a reserved
// type ends the list there, and a VLR that describes more bytes than the
// records hold is ignored, as LAS 1.4 R15 says ("extra bytes mismatch").
// GeoTIFF-key CRSs are not translated: crs_wkt stays empty for them.
// Throws sapmvs::InputError naming the file and what was expected when it is
// not LAS, truncated, LAZ-compressed or of an unknown point format.
LasCloud ReadLas(const std::filesystem::path& path, bool extra_values = false);

// Writes `X Y Z` lines with `precision` decimals, or `X Y Z R G B` with 8-bit
// colour (ColorTo8) when `rgb`, atomically.
void WriteXyz(const std::filesystem::path& path, const std::vector<PointRecord>& points,
              int precision = 3, bool rgb = false);

struct XyzCloud {
  std::vector<PointRecord> points;
  bool has_rgb = false;
};

// Reads `X Y Z` or `X Y Z R G B` lines (whitespace or comma separated, the
// same layout on every line; 8-bit colour 0-255; blank and `#` lines skipped).
// Throws sapmvs::InputError naming file:line for a malformed line or a
// non-finite value.
XyzCloud ReadXyz(const std::filesystem::path& path);

}  // namespace sapmvs

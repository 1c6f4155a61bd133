#pragma once
// `sapmvs evaluate`: the height accuracy of a dense cloud against airborne
// LiDAR or a DSM raster, with the paper's protocol (docs: method.md section 6.1;
// the paper's Tables 9-11).
//
// Against LiDAR, a cloud point's reference height is the mean Z of the LiDAR
// points within horizontal (XY) distance d of it; against a DSM it is the
// DSM bilinearly interpolated at the point's XY. Either way dz = Z - Z_ref.
// Points on building edges meet LiDAR from the other side of the edge and get
// large "pseudo-errors"; the paper repeats the statistics after dropping
// points with |dz| > T, one row per threshold T.
//
// Coordinates stay in double: a UTM northing (~5.4e6) in float32 is quantised
// to 0.5 m.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/evaluate/dsm_completeness.h"

namespace sapmvs {

struct GeoRaster;

// The default d is this factor times the LiDAR's measured point spacing (the
// median XY distance from a LiDAR point to its nearest distinct neighbour).
// On a regular grid of spacing s the disc then holds the 13 points nearest its
// centre, and a point anywhere between grid nodes still has at least 9; at the
// paper's 4 points/m^2 (s = 0.5 m) it gives d = 1 m.
constexpr double kRadiusPerSpacing = 2.0;
// The largest --radius accepted, in LiDAR spacings (~8,000 points per query).
constexpr double kMaxRadiusPerSpacing = 50.0;

struct EvaluateOptions {
  // The dense cloud, by extension: .ply, .las, or .xyz / .txt (X Y Z lines).
  std::filesystem::path cloud;
  // The reference, by extension: LiDAR points (.las, .xyz, .txt, .ply) or a
  // DSM raster GDAL reads (.tif, .tiff, .vrt, .img, .asc), in the cloud's CRS.
  std::filesystem::path reference;
  // LiDAR only: d, the XY search radius in CRS units (a LiDAR point at
  // distance exactly d counts). 0 = kRadiusPerSpacing x the measured spacing.
  double radius = 0;
  // |dz| <= tolerance counts as "within tolerance", in CRS units. The paper's
  // 1 m; a block without a metric frame should pass a value in its own units
  // (a few GSD).
  double tolerance = 1;
  // Pseudo-error thresholds T, CRS units, each > 0: one extra row per value,
  // in the order given, leaving out points with |dz| > T.
  std::vector<double> drop_above;
  // DSM only, for completeness: the evaluated footprint as xmin, ymin, xmax,
  // ymax in CRS units; DSM cells whose centre lies inside (edges included).
  // Empty = none.
  std::vector<double> footprint;
  // DSM only, for completeness, instead of `footprint`: a block file or
  // folder; the footprint is the DSM cells whose centre, at the DSM height,
  // projects into at least 2 of its images.
  std::filesystem::path block;
  // Write the report as JSON here (atomically); empty = no JSON.
  std::filesystem::path json;
  // Write dz_histogram.png, dz_map.png and pseudo_errors.png into this
  // folder (created when missing); empty = no plots.
  std::filesystem::path plots;
  // A folder `sapmvs run` wrote: the report also goes into it as
  // evaluation.json, the plots into its evaluation/, and its report.html is
  // made again with them (report/report_html.h). Empty = none.
  std::filesystem::path run;
  // No progress bar.
  bool quiet = false;

  // Empty when the options are usable, else one line naming the flag at
  // fault and what was expected.
  std::string Problem() const;
  bool Check() const { return Problem().empty(); }
};

enum class ReferenceKind { kLidar, kDsm };

// What `path` is used as, from its extension; throws sapmvs::Error naming
// the path and the extensions accepted.
ReferenceKind DetectReferenceKind(const std::filesystem::path& path);

// The statistics of one row of the paper's tables.
struct ErrorRow {
  // Points with |dz| > threshold are left out as pseudo-errors; +inf for the
  // first row (no threshold).
  double threshold = std::numeric_limits<double>::infinity();
  long checkpoints = 0;  // points with a reference height and |dz| <= threshold
  long dropped = 0;      // points with a reference height and |dz| > threshold
  // Over the checkpoints, CRS units; NaN without checkpoints.
  double rmse = std::numeric_limits<double>::quiet_NaN();     // sqrt(mean dz^2)
  double max_abs = std::numeric_limits<double>::quiet_NaN();  // largest |dz|
  double mean = std::numeric_limits<double>::quiet_NaN();     // mean dz (> 0: cloud above)
  // Median |dz|: the typical error, which a few gross errors do not move.
  double median_abs = std::numeric_limits<double>::quiet_NaN();
  // Share of the checkpoints with |dz| <= tolerance, 0..1.
  double within = std::numeric_limits<double>::quiet_NaN();
};

// One row from per-point errors; NaN entries (points without a reference
// height) are not checkpoints.
ErrorRow ComputeErrorRow(const std::vector<double>& dz, double tolerance,
                         double threshold = std::numeric_limits<double>::infinity());

struct EvaluationReport {
  std::filesystem::path cloud, reference;
  ReferenceKind kind = ReferenceKind::kLidar;
  long cloud_points = 0;
  // LiDAR points, or non-empty DSM cells.
  long reference_points = 0;
  // LiDAR: the measured spacing (see kRadiusPerSpacing), d, and how d was
  // chosen. NaN / empty for a DSM.
  double spacing = std::numeric_limits<double>::quiet_NaN();
  double radius = std::numeric_limits<double>::quiet_NaN();
  std::string radius_note;
  // DSM: size and cell size, for the report.
  int dsm_width = 0, dsm_height = 0;
  double dsm_cell_size = 0;
  double tolerance = 1;
  // Cloud points without a reference height: no LiDAR point within d, or
  // outside the DSM / next to empty DSM cells. Never checkpoints.
  long without_reference = 0;
  // The row without a threshold, then one per drop_above value.
  std::vector<ErrorRow> rows;
  // DSM with --footprint or --block.
  std::optional<Completeness> completeness;
  // The horizontal unit of the inputs' CRS, for the plots' axes (raster_io.h
  // CrsLinearUnit; "" when neither the reference nor the cloud has a CRS).
  std::string unit;
  // Per cloud point: position and dz (NaN without a reference height).
  std::vector<Eigen::Vector3d> points;
  std::vector<double> dz;
};

// Reads the XYZ of a cloud (.ply, .las, .xyz/.txt), and its CRS into `crs`
// when given (PLY's comment, LAS's WKT; "" when there is none). Throws
// sapmvs::Error (InputError for malformed files) naming the file; an empty
// cloud is an error.
std::vector<Eigen::Vector3d> ReadCloudPositions(const std::filesystem::path& path,
                                                std::string* crs = nullptr);

// The LiDAR protocol for points in memory; options.cloud / reference only
// label the report, which keeps `cloud` for the plots. Throws sapmvs::Error
// for bad options, an empty input or a non-finite coordinate.
EvaluationReport EvaluateAgainstLidar(std::vector<Eigen::Vector3d> cloud,
                                      const std::vector<Eigen::Vector3d>& lidar,
                                      const EvaluateOptions& options);

// The DSM protocol for points in memory, with completeness when `footprint`
// is given; options.cloud / reference only label the report.
EvaluationReport EvaluateAgainstDsm(std::vector<Eigen::Vector3d> cloud, const GeoRaster& dsm,
                                    const DsmFootprint* footprint, const EvaluateOptions& options);

// Reads the inputs named in `options` and evaluates; with a DSM reference the
// footprint comes from options.footprint or options.block. Output paths are
// checked before any work.
EvaluationReport Evaluate(const EvaluateOptions& options);

// The table on `out`, laid out like the paper's Tables 9-11, with lines for
// d, the points without a reference and completeness.
void PrintEvaluationTable(const EvaluationReport& report, std::ostream& out);

// The report as JSON (no per-point data), written atomically.
void WriteEvaluationJson(const EvaluationReport& report, const std::filesystem::path& path);

// Writes dz_histogram.png, dz_map.png (dz over XY with a colour bar) and
// pseudo_errors.png (the points left out by the largest threshold, or beyond
// the tolerance when no threshold is given) into `dir`, each atomically;
// `dir` is created when missing. Returns the paths written.
std::vector<std::filesystem::path> WriteEvaluationPlots(const EvaluationReport& report,
                                                        const std::filesystem::path& dir);

}  // namespace sapmvs

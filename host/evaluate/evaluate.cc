#include "sapmvs/evaluate/evaluate.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include "evaluate/dsm_reference.h"
#include "evaluate/lidar_reference.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs {
namespace {

std::string LowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

bool IsPointExtension(const std::string& ext) {
  return ext == ".ply" || ext == ".las" || ext == ".xyz" || ext == ".txt";
}

bool IsRasterExtension(const std::string& ext) {
  return ext == ".tif" || ext == ".tiff" || ext == ".vrt" || ext == ".img" || ext == ".asc";
}

void RequirePointExtension(const std::filesystem::path& path) {
  const std::string ext = LowerExtension(path);
  if (ext == ".laz") {
    throw Error(path.string() +
                ": LAZ-compressed clouds are not read; decompress first (laszip, pdal translate)");
  }
  if (!IsPointExtension(ext)) {
    throw Error(path.string() + ": unknown point-cloud extension '" + ext +
                "' (expected .ply, .las, .xyz or .txt)");
  }
}

// Rejects an empty set or a non-finite coordinate, naming `what` and the point.
void CheckPoints(const std::vector<Eigen::Vector3d>& points, const std::string& what) {
  if (points.empty()) throw Error(what + ": no points (expected at least one)");
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw Error(what + ": point " + std::to_string(i) + " (0-based) has a non-finite coordinate");
    }
  }
}

std::string Label(const std::filesystem::path& path, const char* fallback) {
  return path.empty() ? fallback : path.string();
}

// dz for every point, the count without a reference and the rows.
void FillErrors(const std::vector<double>& reference, const EvaluateOptions& o,
                EvaluationReport* r) {
  r->dz.resize(r->points.size());
  for (size_t i = 0; i < r->points.size(); ++i) {
    r->dz[i] = r->points[i].z() - reference[i];
    r->without_reference += std::isnan(reference[i]);
  }
  r->tolerance = o.tolerance;
  r->rows.push_back(ComputeErrorRow(r->dz, o.tolerance));
  for (double t : o.drop_above) r->rows.push_back(ComputeErrorRow(r->dz, o.tolerance, t));
}

void ThrowOnProblem(const EvaluateOptions& o) {
  if (const std::string problem = o.Problem(); !problem.empty()) {
    throw Error("evaluate: " + problem);
  }
}

}  // namespace

std::string EvaluateOptions::Problem() const {
  if (cloud.empty()) return "no cloud given (expected a .ply, .las or .xyz file)";
  if (reference.empty()) return "no --reference given (expected LiDAR points or a DSM raster)";
  if (!(radius >= 0) || !std::isfinite(radius)) {
    return "--radius " + FormatNumber(radius, 10) +
           ": expected a positive distance in CRS units, or 0 to derive it from the LiDAR";
  }
  if (!(tolerance > 0) || !std::isfinite(tolerance)) {
    return "--tolerance " + FormatNumber(tolerance, 10) +
           ": expected a positive distance in CRS units";
  }
  for (double t : drop_above) {
    if (!(t > 0) || !std::isfinite(t)) {
      return "--drop-above " + FormatNumber(t, 10) + ": expected positive thresholds in CRS units";
    }
  }
  if (!footprint.empty()) {
    if (footprint.size() != 4) {
      return "--footprint has " + std::to_string(footprint.size()) +
             " values (expected xmin,ymin,xmax,ymax)";
    }
    if (!(footprint[0] < footprint[2] && footprint[1] < footprint[3]) ||
        !std::all_of(footprint.begin(), footprint.end(),
                     [](double v) { return std::isfinite(v); })) {
      return "--footprint " + FormatNumber(footprint[0], 10) + "," +
             FormatNumber(footprint[1], 10) + "," + FormatNumber(footprint[2], 10) + "," +
             FormatNumber(footprint[3], 10) +
             ": expected finite xmin,ymin,xmax,ymax with xmin < xmax and ymin < ymax";
    }
    if (!block.empty()) return "--footprint and --block both given (expected one of them)";
  }
  return "";
}

ReferenceKind DetectReferenceKind(const std::filesystem::path& path) {
  const std::string ext = LowerExtension(path);
  if (IsRasterExtension(ext)) return ReferenceKind::kDsm;
  if (IsPointExtension(ext)) return ReferenceKind::kLidar;
  if (ext == ".laz") RequirePointExtension(path);  // says how to decompress
  throw Error(path.string() + ": unknown reference extension '" + ext +
              "' (expected LiDAR .las, .xyz, .txt, .ply or a DSM .tif, .tiff, .vrt, .img, .asc)");
}

ErrorRow ComputeErrorRow(const std::vector<double>& dz, double tolerance, double threshold) {
  ErrorRow row;
  row.threshold = threshold;
  double sum = 0, sum2 = 0, max_abs = 0;
  long within = 0;
  std::vector<double> abs_kept;
  for (double d : dz) {
    if (std::isnan(d)) continue;
    const double a = std::abs(d);
    if (a > threshold) {
      ++row.dropped;
      continue;
    }
    ++row.checkpoints;
    sum += d;
    sum2 += d * d;
    max_abs = std::max(max_abs, a);
    within += a <= tolerance;
    abs_kept.push_back(a);
  }
  if (row.checkpoints > 0) {
    const double n = static_cast<double>(row.checkpoints);
    row.rmse = std::sqrt(sum2 / n);
    row.max_abs = max_abs;
    row.mean = sum / n;
    row.within = within / n;
    const size_t half = abs_kept.size() / 2;
    std::nth_element(abs_kept.begin(), abs_kept.begin() + half, abs_kept.end());
    row.median_abs = abs_kept[half];
    if (abs_kept.size() % 2 == 0) {
      row.median_abs =
          0.5 * (row.median_abs + *std::max_element(abs_kept.begin(), abs_kept.begin() + half));
    }
  }
  return row;
}

std::vector<Eigen::Vector3d> ReadCloudPositions(const std::filesystem::path& path,
                                                std::string* crs) {
  RequirePointExtension(path);
  const std::string ext = LowerExtension(path);
  std::vector<Eigen::Vector3d> points;
  if (ext == ".ply") {
    const PointCloud cloud = ReadPly(path);
    if (crs) *crs = cloud.crs;
    points.reserve(cloud.points.size());
    for (const CloudPoint& p : cloud.points) points.push_back(p.position);
  } else {
    std::vector<PointRecord> records;
    if (ext == ".las") {
      LasCloud las = ReadLas(path);
      if (crs) *crs = las.crs_wkt;
      records = std::move(las.points);
    } else {
      records = ReadXyz(path).points;
    }
    points.reserve(records.size());
    for (const PointRecord& p : records) points.emplace_back(p.x, p.y, p.z);
  }
  if (points.empty()) throw Error(path.string() + ": the cloud holds no points (expected some)");
  return points;
}

EvaluationReport EvaluateAgainstLidar(std::vector<Eigen::Vector3d> cloud,
                                      const std::vector<Eigen::Vector3d>& lidar,
                                      const EvaluateOptions& options) {
  ThrowOnProblem(options);
  CheckPoints(cloud, Label(options.cloud, "cloud"));
  CheckPoints(lidar, Label(options.reference, "LiDAR reference"));
  EvaluationReport r;
  r.cloud = options.cloud;
  r.reference = options.reference;
  r.kind = ReferenceKind::kLidar;
  r.cloud_points = static_cast<long>(cloud.size());
  r.reference_points = static_cast<long>(lidar.size());

  const LidarReference reference(lidar);
  r.spacing = reference.MedianSpacing();
  if (options.radius > 0) {
    // The mean over thousands of LiDAR points is no height at a point, and
    // each query would cost as many.
    if (std::isfinite(r.spacing) && options.radius > kMaxRadiusPerSpacing * r.spacing) {
      throw Error("evaluate: --radius " + FormatNumber(options.radius, 10) + " is " +
                  FormatNumber(std::round(options.radius / r.spacing), 10) +
                  " x the LiDAR's point spacing (" + FormatNumber(r.spacing, 10) +
                  "); expected at most " + FormatNumber(kMaxRadiusPerSpacing, 10) +
                  " x (--radius <= " + FormatNumber(kMaxRadiusPerSpacing * r.spacing, 10) + ")");
    }
    r.radius = options.radius;
    r.radius_note = "given with --radius";
  } else {
    if (std::isnan(r.spacing)) {
      throw Error(Label(options.reference, "LiDAR reference") +
                  ": cannot measure the point spacing (fewer than 2 distinct XY positions); "
                  "give --radius");
    }
    r.radius = kRadiusPerSpacing * r.spacing;
    r.radius_note =
        FormatNumber(kRadiusPerSpacing, 10) + " x the LiDAR's median nearest-neighbour XY spacing";
  }
  const std::vector<double> heights = reference.MeanHeights(cloud, r.radius, !options.quiet);
  r.points = std::move(cloud);
  FillErrors(heights, options, &r);
  return r;
}

EvaluationReport EvaluateAgainstDsm(std::vector<Eigen::Vector3d> cloud, const GeoRaster& dsm,
                                    const DsmFootprint* footprint, const EvaluateOptions& options) {
  ThrowOnProblem(options);
  CheckPoints(cloud, Label(options.cloud, "cloud"));
  EvaluationReport r;
  r.cloud = options.cloud;
  r.reference = options.reference;
  r.kind = ReferenceKind::kDsm;
  r.cloud_points = static_cast<long>(cloud.size());
  r.dsm_width = dsm.width;
  r.dsm_height = dsm.height;
  r.dsm_cell_size = dsm.cell_size;
  for (int row = 0; row < dsm.height; ++row) {
    for (int c = 0; c < dsm.width; ++c) r.reference_points += !dsm.IsEmpty(c, row);
  }
  if (r.reference_points == 0) {
    throw Error(Label(options.reference, "DSM") + ": every cell is empty (nodata)");
  }
  std::vector<double> heights(cloud.size());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(cloud.size()); ++i) {
    heights[i] = DsmHeight(dsm, cloud[i].x(), cloud[i].y());
  }
  r.points = std::move(cloud);
  FillErrors(heights, options, &r);
  if (footprint) {
    r.completeness = ComputeCompleteness(dsm, *footprint, r.points, r.dz, options.tolerance);
  }
  return r;
}

EvaluationReport Evaluate(const EvaluateOptions& options) {
  ThrowOnProblem(options);
  const ReferenceKind kind = DetectReferenceKind(options.reference);
  RequirePointExtension(options.cloud);
  if (kind == ReferenceKind::kLidar && (!options.footprint.empty() || !options.block.empty())) {
    throw Error(options.reference.string() +
                ": --footprint and --block apply to a DSM reference, this is LiDAR");
  }
  if (kind == ReferenceKind::kDsm && options.radius > 0) {
    throw Error(options.reference.string() + ": --radius applies to LiDAR, this is a DSM");
  }
  // Output paths fail now, not after minutes of work.
  if (!options.json.empty()) {
    const std::filesystem::path dir =
        options.json.parent_path().empty() ? "." : options.json.parent_path();
    if (!std::filesystem::is_directory(dir)) {
      throw Error(options.json.string() + ": cannot write, directory " + dir.string() +
                  " does not exist");
    }
  }
  if (!options.run.empty() && !std::filesystem::is_regular_file(options.run / "report.json")) {
    throw Error(options.run.string() +
                ": --run expects a folder `sapmvs run` wrote (it has no report.json)");
  }
  if (!options.plots.empty() && std::filesystem::exists(options.plots) &&
      !std::filesystem::is_directory(options.plots)) {
    throw Error(options.plots.string() + ": --plots expects a folder, this is a file");
  }

  std::string cloud_crs, reference_crs;
  std::vector<Eigen::Vector3d> cloud = ReadCloudPositions(options.cloud, &cloud_crs);
  // The plots' axes are labelled with the reference's unit, else the cloud's.
  auto with_unit = [&](EvaluationReport r) {
    r.unit = CrsLinearUnit(reference_crs.empty() ? cloud_crs : reference_crs);
    return r;
  };
  if (kind == ReferenceKind::kLidar) {
    std::vector<Eigen::Vector3d> lidar = ReadCloudPositions(options.reference, &reference_crs);
    return with_unit(EvaluateAgainstLidar(std::move(cloud), lidar, options));
  }
  const GeoRaster dsm = ReadGeoRaster(options.reference);
  reference_crs = dsm.crs;
  std::optional<DsmFootprint> footprint;
  if (!options.footprint.empty()) {
    const std::vector<double>& b = options.footprint;
    footprint = FootprintFromBox(dsm, b[0], b[1], b[2], b[3]);
  } else if (!options.block.empty()) {
    BlockReadOptions read;
    read.check_image_sizes = false;  // only the orientation is used
    footprint = FootprintFromBlock(dsm, ReadBlock(options.block, read));
  }
  return with_unit(
      EvaluateAgainstDsm(std::move(cloud), dsm, footprint ? &*footprint : nullptr, options));
}

}  // namespace sapmvs

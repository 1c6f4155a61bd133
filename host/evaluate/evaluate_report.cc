// The evaluation report as text (laid out like the paper's Tables 9-11) and
// as JSON.

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <ostream>

#include "sapmvs/evaluate/evaluate.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs {
namespace {

std::string FmtOrDash(const char* format, double v) {
  return std::isnan(v) ? "-" : FormatPrintf(format, v);
}

std::string Percent(long part, long whole) {
  return whole > 0 ? FmtOrDash("%.2f%%", 100.0 * part / whole) : "-";
}

std::string ThresholdLabel(double t) {
  return std::isinf(t) ? std::string("none") : "|dz| <= " + FmtOrDash("%g", t);
}

// A value that JSON can hold: NaN and infinities become null.
nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

void PrintEvaluationTable(const EvaluationReport& r, std::ostream& out) {
  const bool lidar = r.kind == ReferenceKind::kLidar;
  out << "cloud         " << r.cloud.string() << ": " << r.cloud_points << " points\n";
  if (lidar) {
    out << "reference     " << r.reference.string() << ": LiDAR, " << r.reference_points
        << " points, median nearest-neighbour XY spacing " << FmtOrDash("%.4g", r.spacing) << "\n";
    out << "radius d      " << FmtOrDash("%.4g", r.radius) << " (" << r.radius_note << ")\n";
  } else {
    out << "reference     " << r.reference.string() << ": DSM, " << r.dsm_width << " x "
        << r.dsm_height << " cells of " << FmtOrDash("%.4g", r.dsm_cell_size) << ", "
        << r.reference_points << " non-empty; heights bilinear between cell centres\n";
  }
  out << "tolerance     " << FmtOrDash("%g", r.tolerance) << " (" << HeightLabel(r.unit) << ")\n";
  out << "no reference  " << r.without_reference << " of " << r.cloud_points << " points ("
      << Percent(r.without_reference, r.cloud_points) << ") "
      << (lidar ? "have no LiDAR point within d" : "lie outside the DSM or next to empty cells")
      << "; they are not checkpoints\n";
  out << "\n";
  char line[256];
  const std::string within = "within " + FmtOrDash("%g", r.tolerance);
  std::snprintf(line, sizeof line, "%-16s %12s %12s %12s %12s %12s %12s\n", "threshold",
                "checkpoints", "RMSE", "max", "mean", "median |dz|", within.c_str());
  out << line;
  for (const ErrorRow& row : r.rows) {
    std::snprintf(line, sizeof line, "%-16s %12ld %12s %12s %12s %12s %12s\n",
                  ThresholdLabel(row.threshold).c_str(), row.checkpoints,
                  FmtOrDash("%.6f", row.rmse).c_str(), FmtOrDash("%.6f", row.max_abs).c_str(),
                  FmtOrDash("%.6f", row.mean).c_str(), FmtOrDash("%.6f", row.median_abs).c_str(),
                  FmtOrDash("%.1f%%", 100 * row.within).c_str());
    out << line;
  }
  if (r.completeness) {
    const Completeness& c = *r.completeness;
    out << "\ncompleteness  " << FmtOrDash("%.1f%%", 100 * c.share) << ": " << c.filled << " of "
        << c.cells << " non-empty DSM cells in the footprint hold a point within "
        << FmtOrDash("%g", r.tolerance) << "\nfootprint     " << c.footprint << "\n";
  }
}

void WriteEvaluationJson(const EvaluationReport& r, const std::filesystem::path& path) {
  using nlohmann::json;
  json j;
  j["cloud"] = {{"path", r.cloud.string()}, {"points", r.cloud_points}};
  if (r.kind == ReferenceKind::kLidar) {
    j["reference"] = {{"path", r.reference.string()}, {"kind", "lidar"},
                      {"points", r.reference_points}, {"median_spacing", Number(r.spacing)},
                      {"radius", Number(r.radius)},   {"radius_note", r.radius_note}};
  } else {
    j["reference"] = {{"path", r.reference.string()}, {"kind", "dsm"},
                      {"width", r.dsm_width},         {"height", r.dsm_height},
                      {"cell_size", r.dsm_cell_size}, {"non_empty_cells", r.reference_points}};
  }
  j["tolerance"] = r.tolerance;
  j["without_reference"] = r.without_reference;
  j["rows"] = json::array();
  for (const ErrorRow& row : r.rows) {
    j["rows"].push_back({{"threshold", Number(row.threshold)},
                         {"checkpoints", row.checkpoints},
                         {"dropped", row.dropped},
                         {"rmse", Number(row.rmse)},
                         {"max_abs", Number(row.max_abs)},
                         {"mean", Number(row.mean)},
                         {"median_abs", Number(row.median_abs)},
                         {"within_tolerance", Number(row.within)}});
  }
  if (r.completeness) {
    j["completeness"] = {{"footprint", r.completeness->footprint},
                         {"cells", r.completeness->cells},
                         {"filled", r.completeness->filled},
                         {"share", Number(r.completeness->share)}};
  }
  const std::string text = j.dump(2) + "\n";
  WriteStreamAtomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace sapmvs

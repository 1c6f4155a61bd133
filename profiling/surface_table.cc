#include "surface_table.h"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace sapmvs {
namespace {

constexpr double kCellGsd = 4.0;  // ground cover cells and noise radius, GSDs

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

// Medians of the local noise of each groups/group_NNN.ply of a run of
// several groups, ascending; empty for a run of one group.
std::vector<double> GroupNoise(const std::filesystem::path& run, const LocalNoiseOptions& o) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(run / "groups", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("group_", 0) == 0 && e.path().extension() == ".ply") files.push_back(e.path());
  }
  std::vector<double> medians;
  if (files.size() < 2) return medians;
  for (const auto& f : files) {
    const LocalNoise n = MeasureLocalNoise(ReadPly(f), o);
    if (n.sampled > 0) medians.push_back(n.median);
  }
  std::sort(medians.begin(), medians.end());
  return medians;
}

// A run's report.json; discarded (is_discarded()) when unreadable.
nlohmann::json ReadReport(const std::filesystem::path& run) {
  std::ifstream f(run / "report.json");
  return nlohmann::json::parse(f, nullptr, false);
}

// The merge's cross-group duplicates as a share of its input.
std::optional<double> DuplicateShare(const nlohmann::json& j) {
  if (j.is_discarded() || !j.contains("merge")) return std::nullopt;
  const double input = j["merge"].value("input", 0.0);
  if (!(input > 0)) return std::nullopt;
  return j["merge"].value("cross_group_duplicates", 0.0) / input;
}

// NCC evaluations of the run's kernels per point of its cloud (the report's
// stages); none from a binary that does not count them.
std::optional<double> WorkPerPoint(const nlohmann::json& j) {
  if (j.is_discarded() || !j.contains("stages") || !(j.value("points", 0.0) > 0)) {
    return std::nullopt;
  }
  double evaluations = 0;
  for (const nlohmann::json& s : j["stages"]) evaluations += s.value("ncc_evaluations", 0.0);
  if (!(evaluations > 0)) return std::nullopt;
  return evaluations / j["points"].get<double>();
}

}  // namespace

std::string SurfaceTable(const std::vector<SurfaceRow>& rows, double gsd_level) {
  LocalNoiseOptions noise;
  noise.radius = kCellGsd * gsd_level;
  std::vector<std::set<std::pair<int64_t, int64_t>>> cells;
  std::set<std::pair<int64_t, int64_t>> all;
  for (const SurfaceRow& r : rows) {
    cells.push_back(CoveredCells(*r.cloud, kCellGsd * gsd_level));
    all.insert(cells.back().begin(), cells.back().end());
  }
  std::ostringstream t;
  t << "| tool / mode | points | ground covered (" << Fixed(kCellGsd, 0)
    << " GSD cells, share of the union) | local noise median | local noise p90 | median/GSD "
       "| groups' own noise median (lowest–highest) | merged / groups' median "
       "| cross-group duplicates | NCC evaluations per point |\n"
       "|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const SurfaceRow& r = rows[i];
    const LocalNoise n = MeasureLocalNoise(*r.cloud, noise);
    t << "| " << r.name << " | " << r.cloud->points.size() << " | "
      << (all.empty() ? "–" : Fixed(100.0 * cells[i].size() / all.size(), 1) + " %") << " | "
      << (n.sampled ? Fixed(n.median, 4) : "–") << " | " << (n.sampled ? Fixed(n.p90, 4) : "–")
      << " | " << (n.sampled ? Fixed(n.median / gsd_level, 3) : "–") << " | ";
    const std::vector<double> own =
        r.run.empty() ? std::vector<double>() : GroupNoise(r.run, noise);
    if (own.empty()) {
      t << "– | – | ";
    } else {
      const double median = own[own.size() / 2];
      t << Fixed(median, 4) << " (" << Fixed(own.front(), 4) << "–" << Fixed(own.back(), 4)
        << ") | " << (n.sampled ? Fixed(n.median / median, 2) + "×" : "–") << " | ";
    }
    const nlohmann::json report = r.run.empty() ? nlohmann::json() : ReadReport(r.run);
    const std::optional<double> dup = r.run.empty() ? std::nullopt : DuplicateShare(report);
    const std::optional<double> work = r.run.empty() ? std::nullopt : WorkPerPoint(report);
    t << (dup ? Fixed(100 * *dup, 1) + " %" : "–") << " | " << (work ? Fixed(*work, 1) : "–")
      << " |\n";
  }
  return t.str();
}

}  // namespace sapmvs

// Does grouping cost accuracy or completeness where groups meet? Reads a
// whole-block run (DIR/report.json, DIR/cloud.ply) and the simulator's true
// surface, splits the ground into a border zone (within --band of the
// boundary between two groups' cores) and the centre zone (the rest), and
// prints for each: points, share within 1 GSD, median |dz|, coverage. Also
// counts cross-group duplicates: points of different groups within
// --duplicate GSDs of each other (the merge should leave none).
//
// With --per-group, also each group's own cloud (its checkpoint, before the
// merge) against the surface its own images see: does a short group (the
// paper's 4-image groups) cover its ground as well as a 6-image one?
//
// Without truth (a real block), and with it: steps in the run's DSM. For
// every two cells side by side, the height difference; pairs whose cells
// lie in different groups' cores cross a border, the others are inside a
// group. Groups that place the surface differently leave a step where their
// cores meet, and the pairs across borders then differ more than those
// inside.
//
//   group_borders RUN_DIR --block BLOCK [--truth truth/dsm.tif] [--band 20] [--per-group]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>

#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/evaluate/surface_check.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/cloud_merge.h"
#include "sapmvs/util/error.h"

using namespace sapmvs;

namespace {

// The group centres a run's report.json lists.
std::vector<Eigen::Vector2d> ReportCenters(const nlohmann::json& report) {
  std::vector<Eigen::Vector2d> centers;
  for (const auto& g : report.at("groups")) {
    centers.emplace_back(g.at("center")[0].get<double>(), g.at("center")[1].get<double>());
  }
  return centers;
}

// Median, 90th and 99th percentile of `v` (reordered); zeros when empty.
std::array<double, 3> Quantiles(std::vector<double>& v) {
  std::array<double, 3> q = {0, 0, 0};
  if (v.empty()) return q;
  const double at[3] = {0.5, 0.9, 0.99};
  for (int k = 0; k < 3; ++k) {
    const auto nth =
        v.begin() + static_cast<long>(std::min(v.size() - 1, size_t(at[k] * v.size())));
    std::nth_element(v.begin(), nth, v.end());
    q[k] = *nth;
  }
  return q;
}

// Each DSM cell's group core (CoreOwner of `centers`), -1 where empty.
std::vector<int> CellOwners(const GeoRaster& dsm, const std::vector<Eigen::Vector2d>& centers) {
  std::vector<int> owner(dsm.values.size(), -1);
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      const Eigen::Vector2d p = dsm.CellCenter(c, r);
      owner[static_cast<size_t>(r) * dsm.width + c] = CoreOwner(centers, p.x(), p.y());
    }
  }
  return owner;
}

// f(a, b, |dz|) for every two filled cells side by side, a and b their
// cell indices.
template <typename F>
void ForEachStep(const GeoRaster& dsm, const F& f) {
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      for (const auto& [dc, dr] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (c + dc >= dsm.width || r + dr >= dsm.height || dsm.IsEmpty(c + dc, r + dr)) continue;
        f(static_cast<size_t>(r) * dsm.width + c, static_cast<size_t>(r + dr) * dsm.width + c + dc,
          std::abs(double(dsm.at(c, r)) - dsm.at(c + dc, r + dr)));
      }
    }
  }
}

// The DSM steps (see the top of this file) of `dsm`, printed. The control
// row: the same borders moved by half the median distance between
// neighbouring group centres (four ways, pooled), where they cut through
// groups' cores: the steps of lines of the same length and shape where no
// groups meet, whose spread says how far the real row may differ by chance
// (a few thousand pairs along a few lines, through trees or over roofs).
void PrintDsmSteps(const GeoRaster& dsm, const std::vector<Eigen::Vector2d>& centers) {
  const std::vector<int> owner = CellOwners(dsm, centers);
  std::vector<double> across, inside;
  ForEachStep(dsm, [&](size_t a, size_t b, double dz) {
    (owner[a] == owner[b] ? inside : across).push_back(dz);
  });
  std::vector<double> nearest;
  for (size_t g = 0; g < centers.size(); ++g) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t h = 0; h < centers.size(); ++h) {
      if (h != g) best = std::min(best, (centers[g] - centers[h]).norm());
    }
    nearest.push_back(best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  const double shift = 0.5 * nearest[nearest.size() / 2];
  std::vector<double> control;
  for (const Eigen::Vector2d& d : {Eigen::Vector2d(shift, 0), Eigen::Vector2d(-shift, 0),
                                   Eigen::Vector2d(0, shift), Eigen::Vector2d(0, -shift)}) {
    std::vector<Eigen::Vector2d> moved = centers;
    for (Eigen::Vector2d& c : moved) c += d;
    const std::vector<int> fake = CellOwners(dsm, moved);
    ForEachStep(dsm, [&](size_t a, size_t b, double dz) {
      if (owner[a] == owner[b] && fake[a] != fake[b]) control.push_back(dz);
    });
  }
  std::cout << "DSM steps (cell " << dsm.cell_size << "): neighbouring cells' |dz|\n"
            << "pairs              count     median        p90        p99\n";
  const std::pair<const char*, std::vector<double>*> sets[] = {
      {"inside groups", &inside}, {"across borders", &across}, {"control", &control}};
  for (const auto& [name, v] : sets) {
    const std::array<double, 3> q = Quantiles(*v);
    std::cout << std::left << std::setw(14) << name << std::right << std::setw(10) << v->size()
              << std::fixed << std::setprecision(4) << std::setw(11) << q[0] << std::setw(11)
              << q[1] << std::setw(11) << q[2] << "\n";
    std::cout.unsetf(std::ios::floatfield);
  }
}

nlohmann::json ReadReport(const std::filesystem::path& dir) {
  std::ifstream f(dir / "report.json");
  if (!f) throw Error((dir / "report.json").string() + ": cannot read");
  return nlohmann::json::parse(f);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Accuracy and completeness of a run at group borders vs group centres");
  std::string run_dir, block_path, truth_path, zones_dir;
  double band_gsd = 20, duplicate_gsd = 0.25;
  int level = 1;
  app.add_option("run", run_dir, "Output folder of `sapmvs run`")->required();
  app.add_option("--block", block_path, "The block that was run")->required();
  app.add_option("--truth", truth_path,
                 "True surface raster (truth/dsm.tif); without it only the DSM steps");
  app.add_option("--band", band_gsd, "Border zone half-width, block GSDs")->capture_default_str();
  app.add_option("--duplicate", duplicate_gsd, "Cross-group duplicate distance, block GSDs")
      ->capture_default_str();
  app.add_option("--zones-from", zones_dir,
                 "Take the group centres from this run instead (e.g. to measure a one-group "
                 "run over the zones of a grouped one)");
  app.add_option("--level", level, "Pyramid level matched (coverage cells)")->capture_default_str();
  double tolerance_gsd = 1;
  app.add_option("--tolerance", tolerance_gsd,
                 "Height tolerance of a right point (and of a covered cell), block GSDs")
      ->capture_default_str();
  bool per_group = false;
  app.add_flag("--per-group", per_group,
               "Also each group's checkpoint cloud against the cells its own images see");
  CLI11_PARSE(app, argc, argv);
  try {
    const std::filesystem::path dir(run_dir);
    const nlohmann::json report = ReadReport(dir);
    std::vector<int> group_of;
    for (const auto& g : report.at("groups")) {
      const long kept = g.at("kept_after_merge").get<long>();
      group_of.insert(group_of.end(), kept, g.at("group").get<int>() - 1);
    }
    const std::vector<Eigen::Vector2d> centers =
        ReportCenters(zones_dir.empty() ? report : ReadReport(zones_dir));
    const PointCloud cloud = ReadPly(dir / "cloud.ply");
    if (group_of.size() != cloud.points.size()) {
      throw Error("report.json's kept_after_merge counts do not add up to cloud.ply's points");
    }
    const Block block = ReadBlock(block_path);
    if (centers.size() > 1) PrintDsmSteps(ReadGeoRaster(dir / "dsm.tif"), centers);
    if (truth_path.empty()) return 0;
    const GeoRaster truth = ReadGeoRaster(truth_path);
    const double gsd = EstimateBlockGeometry(block).gsd_median;
    const double band = band_gsd * gsd;
    SurfaceCheckOptions so;
    so.tolerance = tolerance_gsd * gsd;
    so.cell_size = 2 * std::ldexp(1.0, level) * gsd;
    const std::optional<GeoRaster> classes = ReadClassRasterBeside(truth_path);
    if (classes) so.classes = &*classes;
    std::cout << "run " << run_dir << ": " << cloud.points.size() << " points, " << centers.size()
              << " groups; GSD " << gsd << ", border band +-" << band << " (" << band_gsd
              << " GSD); within = within " << tolerance_gsd << " GSD\n";
    std::cout << "zone        points    within  median|dz|  coverage  (cells seen)\n";
    for (const bool border : {true, false}) {
      so.region = [&](double x, double y) {
        return centers.size() > 1 && (CoreOwnerAndBorder(centers, x, y).second <= band) == border;
      };
      if (centers.size() < 2 && border) continue;
      if (centers.size() < 2) so.region = nullptr;
      const SurfaceCheck s = CheckAgainstSurface(cloud, truth, block, so);
      std::cout << std::left << std::setw(8) << (border ? "border" : "centre") << std::right
                << std::setw(10) << s.checked << std::fixed << std::setprecision(1) << std::setw(9)
                << 100 * s.share_within << "%" << std::setprecision(3) << std::setw(12)
                << s.median_abs_dz << std::setprecision(1) << std::setw(9) << 100 * s.coverage
                << "%  (" << s.cells_seen << ")\n";
      std::cout.unsetf(std::ios::floatfield);
    }
    if (per_group) {
      so.region = nullptr;
      std::cout << "group  images    points    within  median|dz|  coverage  (cells seen by "
                << so.min_images << "+ of its images)\n";
      for (const auto& g : report.at("groups")) {
        const int index = g.at("group").get<int>();
        Block sub = block;
        sub.images.clear();
        for (const auto& name : g.at("images")) {
          const int i = block.FindImage(name.get<std::string>());
          if (i < 0) throw Error("report.json names image " + name.dump() + " not in the block");
          sub.images.push_back(block.images[i]);
        }
        char file[32];
        std::snprintf(file, sizeof(file), "group_%03d.ply", index);
        const PointCloud own = ReadPly(dir / "groups" / file);
        const SurfaceCheck s = CheckAgainstSurface(own, truth, sub, so);
        std::cout << std::setw(5) << index << std::setw(8) << sub.images.size() << std::setw(10)
                  << s.checked << std::fixed << std::setprecision(1) << std::setw(9)
                  << 100 * s.share_within << "%" << std::setprecision(3) << std::setw(12)
                  << s.median_abs_dz << std::setprecision(1) << std::setw(9) << 100 * s.coverage
                  << "%  (" << s.cells_seen << ")\n";
        std::cout.unsetf(std::ios::floatfield);
      }
    }
    std::cout << std::setprecision(6) << "cross-group pairs within " << duplicate_gsd
              << " GSD: " << CountCrossGroupPairs(cloud, group_of, duplicate_gsd * gsd) << "\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

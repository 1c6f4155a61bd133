// SAPMVS against PMVS on one block, in one run (method.md 3.6, 3.10; the paper's
// Tables 4 and 6): wall time, points, accuracy and coverage against the true
// surface, and the ratios. Both modes share one OpenCL context, so kernels
// are compiled before the first timing starts.
//
//   compare_modes BLOCK --truth DSM [--csv FILE] [matcher flags of `sapmvs run`]
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>

#include "device/make_patch_kernels.h"
#include "match/patch_kernels.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/evaluate/surface_check.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/util/error.h"
#include "truth_check.h"
#include "util/option_flags.h"

using namespace sapmvs;

struct Row {
  std::string mode;
  double seconds = 0, kernel_seconds = 0;
  long points = 0;
  SurfaceCheck check;
};

int main(int argc, char** argv) {
  CLI::App app("SAPMVS vs PMVS on one block, against its true surface");
  std::string block_path, truth_path, csv_path, device;
  app.add_option("block", block_path, "Block file or folder")->required();
  app.add_option("--truth", truth_path, "True surface raster (truth/dsm.tif)")->required();
  app.add_option("--device", device, "OpenCL device, or reference (the CPU reference)");
  app.add_option("--csv", csv_path, "Write the rows as CSV");
  double coverage_cells = 1;
  app.add_option("--coverage-cells", coverage_cells,
                 "Coverage cell side in nominal point spacings (csize pixels at the level)")
      ->capture_default_str();
  std::string only;
  MatcherOptions base;
  app.add_option("--only", only, "Run one mode: sapmvs or pmvs");
  bool window_bound = false;
  app.add_flag("--window-bound", window_bound,
               "Also print the coverage a window matcher could reach at all "
               "(WindowCoverageBound, half-width wsize/2 working pixels)");
  // Every matcher flag of `sapmvs run` but --mode (both modes run here).
  cli::AddOptionFlags(&app, &base, cli::CompareModesMatcherFields());
  CLI11_PARSE(app, argc, argv);
  try {
    if (const std::string problem = base.Problem(); !problem.empty())
      throw Error("expected " + problem);
    const int level = base.level;
    const Block block = ReadBlock(block_path);
    // With the simulator's classes.tif beside the truth the rows split by class.
    const Truth truth_data = ReadTruth(truth_path);
    const GeoRaster& truth = truth_data.surface;
    const std::optional<GeoRaster>& classes = truth_data.classes;
    const double gsd = EstimateBlockGeometry(block).gsd_median;  // full resolution
    const SurfaceCheckOptions so =
        TruthCheckOptions(truth_data, gsd, level, coverage_cells * base.cell_size);
    const double coverage_cell = so.cell_size;
    PatchKernelsOptions dev;
    dev.device = device;
    dev.profile = true;
    const std::unique_ptr<PatchKernels> kernels = MakePatchKernels(dev);
    std::vector<Row> rows;
    std::vector<MatchMode> modes = {MatchMode::kPmvs, MatchMode::kSapmvs};
    if (!only.empty()) modes = {ParseMatchMode(only)};
    for (const MatchMode mode : modes) {
      MatcherOptions o = base;
      o.mode = mode;
      o.progress = false;
      // Warm-up on a tiny budget compiles every kernel of this mode.
      MatcherOptions warm = o;
      warm.max_waves = 1;
      warm.use_edges = false;
      (void)MatchGroup(block, {}, warm, *kernels);
      const auto start = std::chrono::steady_clock::now();
      const MatchResult r = MatchGroup(block, {}, o, *kernels);
      Row row;
      row.mode = ToString(mode);
      row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (const auto& [name, t] : r.stats.kernels) row.kernel_seconds += t.seconds;
      row.points = r.stats.points;
      row.check = CheckAgainstSurface(r.cloud, truth, block, so);
      if (const char* dump = std::getenv("SAPMVS_DUMP_DZ")) {
        std::ofstream d(std::string(dump) + "_" + row.mode + ".txt");
        for (const CloudPoint& cp : r.cloud.points) {
          const int col = static_cast<int>((cp.position.x() - truth.origin_x) / truth.cell_size);
          const int rr = static_cast<int>((truth.origin_y - cp.position.y()) / truth.cell_size);
          if (col < 0 || rr < 0 || col >= truth.width || rr >= truth.height) continue;
          d << std::setprecision(12) << cp.position.x() << " " << cp.position.y() << " "
            << cp.position.z() - truth.at(col, rr) << " " << cp.normal.z() << " " << cp.score << " "
            << cp.num_views << "\n";
        }
      }
      rows.push_back(row);
      std::cerr << row.mode << ": " << r.stats.patches << " patches, " << r.stats.waves
                << " waves, " << r.stats.candidates << " candidates, filter "
                << r.stats.points_before_filter << " -> " << r.stats.points << ", score floor "
                << r.stats.score_floor << " (" << r.stats.removed_score
                << " below), plane tolerance " << r.stats.plane_tolerance << "\n";
    }
    std::cout << "block " << block_path << ", level " << level << ", GSD " << gsd
              << " (tolerance 1 GSD; coverage cells of " << coverage_cell << ")\n";
    std::cout << std::left << std::setw(8) << "mode" << std::right << std::setw(10) << "wall s"
              << std::setw(11) << "kernel s" << std::setw(10) << "points" << std::setw(12)
              << "<=1 GSD" << std::setw(12) << "median|dz|" << std::setw(11) << "coverage"
              << "\n";
    for (const Row& r : rows) {
      std::cout << std::left << std::setw(8) << r.mode << std::right << std::fixed
                << std::setprecision(2) << std::setw(10) << r.seconds << std::setw(11)
                << r.kernel_seconds << std::setw(10) << r.points << std::setw(11)
                << std::setprecision(1) << 100 * r.check.share_within << "%" << std::setw(12)
                << std::setprecision(3) << r.check.median_abs_dz << std::setw(10)
                << std::setprecision(1) << 100 * r.check.coverage << "%\n";
    }
    if (classes) {
      std::cout << "by class (2 ground, 5 trees, 6 roofs, 9 water; water cells are not counted as "
                   "seen):\n";
      for (const Row& r : rows) {
        for (const auto& [k, c] : r.check.by_class) {
          std::cout << "  " << std::left << std::setw(8) << r.mode << "class " << std::setw(3) << k
                    << std::right << std::setw(9) << c.checked << " pts" << std::setw(7)
                    << std::setprecision(1) << (c.checked ? 100.0 * c.within / c.checked : 0.0)
                    << "% within" << std::setw(9) << c.cells_seen << " cells" << std::setw(7)
                    << (c.cells_seen ? 100.0 * c.cells_covered / c.cells_seen : 0.0)
                    << "% covered\n";
        }
      }
    }
    if (window_bound) {
      const double radius = (base.window_size / 2) * std::ldexp(1.0, level) * gsd;
      const WindowBound b = WindowCoverageBound(truth, block, so, radius);
      std::cout << std::setprecision(1) << "window bound (" << base.window_size << "x"
                << base.window_size << ", half-width " << std::setprecision(2) << radius << "): of "
                << b.cells_seen << " seen cells, a window centred there fits "
                << std::setprecision(1) << 100.0 * b.centred / std::max(1L, b.cells_seen)
                << "%, one containing the cell " << 100.0 * b.any / std::max(1L, b.cells_seen)
                << "%\n";
    }
    if (rows.size() == 2) {
      const Row& p = rows[0];
      const Row& s = rows[1];
      std::cout << std::setprecision(2) << "sapmvs/pmvs: speed " << p.seconds / s.seconds
                << "x, points " << static_cast<double>(s.points) / p.points << "x\n";
    }
    if (!csv_path.empty()) {
      std::ofstream csv(csv_path);
      csv << "mode,wall_s,kernel_s,points,within_1gsd,median_abs_dz,coverage\n";
      for (const Row& r : rows) {
        csv << r.mode << "," << r.seconds << "," << r.kernel_seconds << "," << r.points << ","
            << r.check.share_within << "," << r.check.median_abs_dz << "," << r.check.coverage
            << "\n";
      }
    }
  } catch (const Error& e) {
    std::cerr << "compare_modes: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

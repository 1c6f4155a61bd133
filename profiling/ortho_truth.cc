// How close is a true orthophoto to the simulator's? Reads an orthophoto
// (8-bit RGBA GeoTIFF, alpha 0 = empty; e.g. a run's ortho.tif) and the
// truth of the simulated block it was made from (truth/ortho.tif, the scene's
// cell tops seen straight down, and truth/dsm.tif), on whatever grids they
// have, and prints one row: coverage, the luminance error and its bias (the
// exposure), the shift phase correlation finds in tiles (where the ortho's
// DSM or its georeferencing puts things), and the share of edge cells beside
// a wall or crown that show the other side's colour, for roofs and for the
// ground (a roof leaning onto the street: what a true ortho must not show).
// The definitions are in ortho_truth_metrics.h.
//
//   ortho_truth ORTHO.tif --truth SIM/truth [--dsm RUN/dsm.tif] [--tile 64] [--json FILE]
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "ortho_truth_metrics.h"
#include "sapmvs/util/error.h"
#include "util/option_flags.h"

using namespace sapmvs;

namespace {

nlohmann::json ToJson(const OrthoTruth& r, const std::string& ortho) {
  auto side = [](const EdgeSide& s) {
    return nlohmann::json{{"cells", s.cells}, {"wrong", s.wrong}, {"share", s.Share()}};
  };
  nlohmann::json tiles = nlohmann::json::array();
  for (const auto& t : r.tile_shifts) tiles.push_back({t.col, t.row, t.east, t.north});
  nlohmann::json wrong = nlohmann::json::array();
  for (const auto& w : r.wrong_cells) {
    wrong.push_back({{"col", w.col},
                     {"row", w.row},
                     {"x", w.x},
                     {"y", w.y},
                     {"side", w.high ? "roof" : "ground"},
                     {"dsm_right", w.dsm_right},
                     {"step_right", w.step_right}});
  }
  return {{"ortho", ortho},
          {"gsd", r.gsd},
          {"ortho_cell", r.ortho_cell},
          {"coverage", r.Coverage()},
          {"truth_cells", r.truth_cells},
          {"covered_cells", r.covered_cells},
          {"compared_cells", r.compared_cells},
          {"luminance_median", r.luminance_median},
          {"luminance_p95", r.luminance_p95},
          {"luminance_bias", r.luminance_bias},
          {"tiles", r.tiles},
          {"tiles_used", r.tiles_used},
          {"shift_median_gsd", r.shift_median},
          {"shift_p95_gsd", r.shift_p95},
          {"shift_east_gsd", r.shift_east},
          {"shift_north_gsd", r.shift_north},
          {"tile_shifts", tiles},  // [column, row, east, north]: GSDs
          {"ghost_high", side(r.high)},
          {"ghost_low", side(r.low)},
          {"ghost_high_dsm_right", side(r.high_right)},
          {"ghost_low_dsm_right", side(r.low_right)},
          {"ghost_high_step_right", side(r.high_step_right)},
          {"ghost_low_step_right", side(r.low_step_right)},
          {"wrong_cells", wrong}};  // each edge cell of the wrong side
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("An orthophoto against the simulator's true orthophoto");
  std::string ortho_path, truth_dir, json_path, dsm_path;
  OrthoTruthOptions options;
  app.add_option("ortho", ortho_path, "Orthophoto, 8-bit RGBA GeoTIFF (alpha 0 = empty)")
      ->required();
  app.add_option("--truth", truth_dir, "The simulated block's truth folder (ortho.tif, dsm.tif)")
      ->required();
  app.add_option("--json", json_path, "Also write the numbers to this JSON file");
  app.add_option(
      "--dsm", dsm_path,
      "The DSM the ortho was made on (a run's dsm.tif): also the wrong sides where it is "
      "right");
  cli::AddOptionFlags(&app, &options);
  CLI11_PARSE(app, argc, argv);
  try {
    const std::filesystem::path truth_path(truth_dir);
    const ColorRaster ortho = ReadColorRaster(ortho_path);
    const ColorRaster truth = ReadColorRaster(truth_path / "ortho.tif");
    const GeoRaster dsm = ReadGeoRaster(truth_path / "dsm.tif");
    std::optional<GeoRaster> ortho_dsm;
    if (!dsm_path.empty()) ortho_dsm = ReadGeoRaster(dsm_path);
    const OrthoTruth r = [&] {
      try {
        return CompareOrthoToTruth(ortho, truth, dsm, options, ortho_dsm ? &*ortho_dsm : nullptr);
      } catch (const Error& e) {
        throw Error(ortho_path + ": " + e.what());
      }
    }();
    std::cout << "ortho " << ortho_path << ": " << ortho.grid.width << " x " << ortho.grid.height
              << " cells of " << r.ortho_cell << " (" << r.ortho_cell / r.gsd << " GSD); truth GSD "
              << r.gsd << "\n";
    char row[256];
    std::snprintf(row, sizeof(row),
                  "%8.1f%% %13.2f %6.2f %+7.2f %11s %15.2f %6.2f %+6.2f %+6.2f %17.1f%% %7.1f%%\n",
                  100 * r.Coverage(), r.luminance_median, r.luminance_p95, r.luminance_bias,
                  (std::to_string(r.tiles_used) + "/" + std::to_string(r.tiles)).c_str(),
                  r.shift_median, r.shift_p95, r.shift_east, r.shift_north, 100 * r.high.Share(),
                  100 * r.low.Share());
    std::cout << " coverage  |dY| median    p95    bias       tiles  |shift| median    p95   east  "
                 "north  wrong side: roofs   ground\n"
              << row << "(|dY|, bias: luminance, 8-bit levels; shift: truth GSDs, of the tiles "
              << "used; wrong side: of " << r.high.cells << " roof and " << r.low.cells
              << " ground edge cells)\n";
    if (ortho_dsm) {
      std::printf(
          "where the DSM is right (within %g GSD): wrong side %.1f%% of %ld roof, %.1f%% of "
          "%ld ground edge cells\n",
          options.dsm_tolerance_gsd, 100 * r.high_right.Share(), r.high_right.cells,
          100 * r.low_right.Share(), r.low_right.cells);
      std::printf(
          "and right across the step too: wrong side %.1f%% of %ld roof, %.1f%% of %ld ground "
          "edge cells\n",
          100 * r.high_step_right.Share(), r.high_step_right.cells, 100 * r.low_step_right.Share(),
          r.low_step_right.cells);
    }
    if (!json_path.empty()) {
      std::ofstream f(json_path);
      f << ToJson(r, ortho_path).dump(2) << "\n";
      if (!f) throw Error(json_path + ": cannot write");
    }
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

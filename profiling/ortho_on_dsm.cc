// The true orthophoto of a block over a DSM it is given, as `sapmvs run`
// makes it over its own. Over a simulated block's truth/dsm.tif taken onto
// a run's DSM cells (`--cells-of RUN/dsm.tif`: each of the run's filled
// cells gets the median true height inside it), it shows what the ortho
// does with a DSM that is right at the run's resolution: ortho_truth's
// counts there are the floor that the cells and the pixels alone leave (a
// DSM cell of 3.5 GSD puts a roof's step up to 1.75 GSD from the true one,
// and a pixel of 2 GSD at a roof's edge half covers what lies beyond).
//
//   ortho_on_dsm BLOCK --dsm DSM.tif --cell C [--level 1] --out ORTHO.tif
//                [--cells-of RUN_DSM.tif --write-dsm USED_DSM.tif]
//
// C: the ortho cell, CRS units (a run's report.json, "ortho" "cell").
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <vector>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/ortho/true_ortho.h"
#include "sapmvs/util/error.h"
#include "util/option_flags.h"

using namespace sapmvs;

namespace {

// `fine` onto the cells of `grid` that are filled: the median of the fine
// cells whose centres fall in each; empty where none does.
GeoRaster MedianOnto(const GeoRaster& fine, const GeoRaster& grid) {
  GeoRaster out = grid;
  std::vector<std::vector<float>> heights(grid.values.size());
  for (int r = 0; r < fine.height; ++r) {
    for (int c = 0; c < fine.width; ++c) {
      if (fine.IsEmpty(c, r)) continue;
      const Eigen::Vector2d p = fine.CellCenter(c, r);
      const int gc = static_cast<int>(std::floor((p.x() - grid.origin_x) / grid.cell_size));
      const int gr = static_cast<int>(std::floor((grid.origin_y - p.y()) / grid.cell_size));
      if (gc < 0 || gr < 0 || gc >= grid.width || gr >= grid.height || grid.IsEmpty(gc, gr)) {
        continue;
      }
      heights[static_cast<size_t>(gr) * grid.width + gc].push_back(fine.at(c, r));
    }
  }
  for (size_t i = 0; i < heights.size(); ++i) {
    std::vector<float>& h = heights[i];
    out.values[i] = out.nodata;
    if (h.empty()) continue;
    std::nth_element(h.begin(), h.begin() + h.size() / 2, h.end());
    out.values[i] = h[h.size() / 2];
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("A block's true orthophoto over a given DSM");
  std::string block_path, dsm_path, out_path, cells_path, write_dsm_path;
  int level = 1;
  double cell = 0;
  OrthoOptions options;
  app.add_option("block", block_path, "The block (as `sapmvs run` reads it)")->required();
  app.add_option("--dsm", dsm_path, "The DSM to drape the images over (GeoTIFF, block CRS)")
      ->required();
  app.add_option("--cell", cell, "Ortho cell, CRS units")->required()->check(CLI::PositiveNumber);
  app.add_option("--level", level, "Pyramid level of the images")->check(CLI::Range(0, 8));
  app.add_option("--out", out_path, "The orthophoto to write (GeoTIFF)")->required();
  app.add_option("--cells-of", cells_path,
                 "Take --dsm onto this DSM's filled cells first (the median inside each)");
  app.add_option("--write-dsm", write_dsm_path, "Also write the DSM used (GeoTIFF)");
  cli::AddOptionFlags(&app, &options);
  CLI11_PARSE(app, argc, argv);
  try {
    const Block block = ReadBlock(block_path);
    GeoRaster dsm = ReadGeoRaster(dsm_path);
    if (!cells_path.empty()) dsm = MedianOnto(dsm, ReadGeoRaster(cells_path));
    if (!write_dsm_path.empty()) WriteGeoTiff(write_dsm_path, dsm);
    const TrueOrtho ortho = MakeTrueOrtho(block, dsm, level, options, cell);
    WriteColorGeoTiff(out_path, ortho.grid, ortho.rgba);
    std::cout << out_path << ": " << ortho.grid.width << " x " << ortho.grid.height << " cells, "
              << ortho.filled_cells << " filled, " << ortho.images_used << " images\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

#pragma once
// An orthophoto against the simulator's true one (truth/ortho.tif, with
// truth/dsm.tif for where buildings and trees stand): how much it covers,
// how far its colours are off, whether it is shifted, and whether roofs were
// drawn onto the ground beside their walls (or ground onto roofs), the
// failure a true orthophoto exists to avoid. profiling/ortho_truth.cc prints
// these; the tests check them on orthos made wrong on purpose.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/option_spec.h"

namespace sapmvs {

// An 8-bit RGB or RGBA raster on a north-up grid.
struct ColorRaster {
  GeoRaster grid;             // geometry and CRS; `values` left empty
  std::vector<uint8_t> rgba;  // 4 per cell, row 0 north; alpha 0 = empty
  bool Filled(int col, int row) const {
    return rgba[(static_cast<size_t>(row) * grid.width + col) * 4 + 3] != 0;
  }
};

// Reads a GeoTIFF (or any raster GDAL opens) of 3 (alpha 255) or 4 8-bit
// bands, flipped north-up when stored south-up. Throws sapmvs::InputError
// naming the file and what was expected.
ColorRaster ReadColorRaster(const std::filesystem::path& path);

struct OrthoTruthOptions {
  // Phase correlation in tiles of tile x tile ortho cells; only tiles this
  // full and with this much texture in the truth (a flat tile has no peak).
  int tile = 64;
  double min_tile_fill = 0.9;
  double min_texture = 4;  // luminance standard deviation, 8-bit levels
  // A DSM step higher than step_gsd truth GSDs makes an edge (a wall, a
  // crown's side); ortho cells within edge_gsd of it are edge cells, whose
  // other side is looked at across_gsd away along the DSM's gradient.
  double step_gsd = 10;
  double edge_gsd = 1;
  double across_gsd = 3;
  // Edge cells whose two sides' true colours are closer than this (RGB
  // distance, 8-bit levels) cannot tell sides apart and are not counted.
  double min_contrast = 12;
  // With the DSM the ortho was draped on: an edge cell where that DSM lies
  // within this many truth GSDs of the true height is one "where the DSM is
  // right", whose wrong side is the ortho's own fault.
  double dsm_tolerance_gsd = 2;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
};

template <class F>
void VisitFields(OrthoTruthOptions& o, F&& f) {
  f(Field(o.tile, "tile")
        .Flag("--tile")
        .In("Comparison")
        .Unit("ortho cells")
        .Range(Between(8, 1024))
        .Help("Side of the phase-correlation tiles, ortho cells"));
  f(Field(o.min_tile_fill, "min_tile_fill")
        .Flag("--min-tile-fill")
        .In("Comparison")
        .Range(Between(0, 1))
        .Help("Least share of a tile the ortho and the truth both fill"));
  f(Field(o.min_texture, "min_texture")
        .Flag("--min-texture")
        .In("Comparison")
        .Unit("levels")
        .Range(AtLeast(0))
        .Help("Least luminance standard deviation of a tile's truth, 8-bit levels"));
  f(Field(o.step_gsd, "step_gsd")
        .Flag("--step")
        .In("Comparison")
        .Unit("GSD")
        .Range(Above(0))
        .Help("DSM step that makes a building or tree edge, truth GSDs"));
  f(Field(o.edge_gsd, "edge_gsd")
        .Flag("--edge-band")
        .In("Comparison")
        .Unit("GSD")
        .Range(AtLeast(0))
        .Help("Distance from a step within which an ortho cell is an edge cell, truth GSDs"));
  f(Field(o.across_gsd, "across_gsd")
        .Flag("--across")
        .In("Comparison")
        .Unit("GSD")
        .Range(Above(0))
        .Help("Distance across the step of the other side's colour, truth GSDs"));
  f(Field(o.min_contrast, "min_contrast")
        .Flag("--min-contrast")
        .In("Comparison")
        .Unit("levels")
        .Range(AtLeast(0))
        .Help("Least RGB distance between the two sides' true colours of a counted edge cell"));
  f(Field(o.dsm_tolerance_gsd, "dsm_tolerance_gsd")
        .Flag("--dsm-tolerance")
        .In("Comparison")
        .Unit("GSD")
        .Range(Above(0))
        .Help("With --dsm: an edge cell's DSM is right within this many truth GSDs"));
}

struct EdgeSide {
  long cells = 0;  // edge cells on this side of their step, both sides told apart
  long wrong = 0;  // whose colour is closer to the other side's
  double Share() const { return cells > 0 ? static_cast<double>(wrong) / cells : 0; }
};

struct OrthoTruth {
  double gsd = 0;         // the truth's cell, CRS units
  double ortho_cell = 0;  // CRS units
  // Truth cells, and those whose centre falls in a filled ortho cell.
  long truth_cells = 0, covered_cells = 0;
  // Ortho cells filled in both: |luminance difference| (Rec. 601, 8-bit
  // levels), and its mean signed value (the ortho's exposure bias).
  long compared_cells = 0;
  double luminance_median = 0, luminance_p95 = 0, luminance_bias = 0;
  // Phase correlation: tiles looked at, tiles used, |shift| in truth GSDs,
  // and the median shift east and north (signed).
  int tiles = 0, tiles_used = 0;
  double shift_median = 0, shift_p95 = 0, shift_east = 0, shift_north = 0;
  // Each used tile's north-west ortho cell (column, row) and its shift east
  // and north in truth GSDs, to find the tiles behind a high percentile.
  struct TileShift {
    int col = 0, row = 0;
    double east = 0, north = 0;
  };
  std::vector<TileShift> tile_shifts;
  EdgeSide high, low;  // roofs and crowns; the ground beside them
  // The same, of the edge cells where the ortho's DSM is right (with one);
  // and of those where it is right on the other side too: where the DSM has
  // the step, so that a wrong colour is the ortho's doing, not the DSM's.
  EdgeSide high_right, low_right;
  EdgeSide high_step_right, low_step_right;
  // Each wrong edge cell, to look at where they are: the ortho cell, its
  // centre, and whether it is a roof's (high) and the DSM is right at it and
  // across the step (with an ortho DSM).
  struct WrongCell {
    int col = 0, row = 0;
    double x = 0, y = 0;
    bool high = false, dsm_right = false, step_right = false;
  };
  std::vector<WrongCell> wrong_cells;
  double Coverage() const {
    return truth_cells > 0 ? static_cast<double>(covered_cells) / truth_cells : 0;
  }
};

// `truth` and `dsm` are the simulator's truth/ortho.tif and truth/dsm.tif;
// the grids may differ from `ortho`'s in cell and extent but must share its
// CRS. Throws sapmvs::Error saying what was expected when the options are
// out of range, the CRSs differ or the ortho misses the truth (the caller
// names the ortho's file).
// `ortho_dsm`, when given, is the DSM the ortho was made on (a run's
// dsm.tif), for high_right, low_right and the step_right pair.
OrthoTruth CompareOrthoToTruth(const ColorRaster& ortho, const ColorRaster& truth,
                               const GeoRaster& dsm, const OrthoTruthOptions& options = {},
                               const GeoRaster* ortho_dsm = nullptr);

}  // namespace sapmvs

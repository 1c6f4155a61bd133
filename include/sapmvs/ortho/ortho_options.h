#pragma once
// How `sapmvs run` makes its true orthophoto (true_ortho.h).
#include <string>

#include "sapmvs/util/option_spec.h"

namespace sapmvs {

struct OrthoOptions {
  // No ortho.tif: for runs that want only the surface.
  bool skip = false;
  // Cell side, CRS units; 0 = the ground sample distance of the level
  // matched, the finest detail the images give at that level.
  double cell_size = 0;
  // Where the chosen image changes, colours are blended over this many cells
  // on each side, so that exposure differences between images do not draw
  // the seam. 0 = a hard seam; at most 7.
  int blend_cells = 3;
  // A DSM cell whose height changes by more than this per unit of horizontal
  // distance to a neighbour (1 = 45 degrees) belongs to an object: a
  // building, a tree. Each object, and the ground a few cells around it, is
  // coloured from one image, so that seams run over open ground, where the
  // images agree, and never cut a roof into parts from different views.
  double object_slope = 1.0;

  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const { return FirstRangeProblem(*this); }
};

template <class F>
void VisitFields(OrthoOptions& o, F&& f) {
  const char* s = "Orthophoto";
  f(Field(o.skip, "skip")
        .Flag("--no-ortho")
        .In(s)
        .Help("Write no orthophoto (ortho.tif, ortho.png)"));
  f(Field(o.cell_size, "cell_size")
        .Flag("--ortho-cell")
        .In(s)
        .Unit("CRS units")
        .Range(AtLeast(0))
        .Help("Orthophoto cell, CRS units (0 = the GSD of the level matched)"));
  f(Field(o.blend_cells, "blend_cells")
        .Flag("--ortho-blend")
        .In(s)
        .Unit("cells")
        .Range(Between(0, 7))
        .Help("Orthophoto: colours blended over this many cells each side of a seam"));
  f(Field(o.object_slope, "object_slope")
        .Flag("--ortho-object-slope")
        .In(s)
        .Range(Above(0))
        .Help("Orthophoto: DSM slope (rise over run) above which cells are an object "
              "(building, tree) taken whole from one image"));
}

}  // namespace sapmvs

#include "truth_check.h"

#include <cmath>

namespace sapmvs {

Truth ReadTruth(const std::filesystem::path& dsm) {
  Truth t;
  t.surface = ReadGeoRaster(dsm);
  t.classes = ReadClassRasterBeside(dsm.string());
  return t;
}

SurfaceCheckOptions TruthCheckOptions(const Truth& truth, double gsd, int level,
                                      double cell_pixels) {
  SurfaceCheckOptions o;
  o.tolerance = gsd;
  o.cell_size = cell_pixels * std::ldexp(1.0, level) * gsd;
  if (truth.classes) o.classes = &*truth.classes;
  return o;
}

SurfaceCheck CheckAgainstTruth(const PointCloud& cloud, const Truth& truth, const Block& block,
                               double gsd, int level, double cell_pixels) {
  return CheckAgainstSurface(cloud, truth.surface, block,
                             TruthCheckOptions(truth, gsd, level, cell_pixels));
}

}  // namespace sapmvs

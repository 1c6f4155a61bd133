#pragma once
// Completeness against a DSM: the footprint of cells that should hold points
// (DsmFootprint) and the share that do (Completeness). Apart from the
// evaluation (evaluate.h) so that the DSM reference (host/evaluate/dsm_reference.h)
// can take them without it.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace sapmvs {

// DSM cells that form the footprint evaluated for completeness.
struct DsmFootprint {
  std::vector<uint8_t> mask;  // row-major like GeoRaster::values; 1 = inside
  std::string note;           // how it was chosen, for the report
};

// Completeness against a DSM: how much of the footprint the cloud covers.
struct Completeness {
  std::string footprint;  // how the footprint was chosen, for the report
  long cells = 0;         // non-empty DSM cells in the footprint
  long filled = 0;        // of those, cells holding a cloud point with |dz| <= tolerance
  double share = std::numeric_limits<double>::quiet_NaN();  // filled / cells
};

}  // namespace sapmvs

#pragma once
// The DSM and footprint of a merged cloud read in chunks (RasterizeDsm and
// MeasureFootprint of cloud_dsm.h, with the same results), holding two bands
// of the raster's heights at a time rather than the block's: each point's
// height goes to the band of raster rows it falls in, spilled to a temporary
// file per band, and the bands' cells take their medians two bands at once.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <vector>

#include "sapmvs/io/ply_stream.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/util/atomic_file.h"

namespace sapmvs {

class StreamedDsm {
 public:
  // The raster over [xmin, xmax] x [ymin, ymax] (the points' extent) with
  // cells of `cell` (DsmCellSize), for `points` points whose first is
  // `first` (MeasureFootprint's grid starts there); band files go to
  // `scratch`, bands of about `band_heights` points (32 MB). Throws what
  // EmptyDsm throws.
  StreamedDsm(const Eigen::Vector3d& first, double xmin, double ymin, double xmax, double ymax,
              double cell, const std::string& crs, long points,
              const std::filesystem::path& scratch, long band_heights = 1 << 22);
  ~StreamedDsm();

  void Add(PointSpan points);
  // The medians, gap-filled by `fill_passes` (DsmOptions::fill_passes).
  GeoRaster Finish(int fill_passes);
  CloudFootprint Footprint() const;

 private:
  struct Height {
    uint32_t cell;  // index into the raster's values (at most 2^28 cells)
    float z;
  };
  struct Band {
    std::vector<Height> buffer;
    std::unique_ptr<AtomicFile> file;  // created at the first spill; never committed
    size_t spilled = 0;
  };
  void Spill(Band* band);

  GeoRaster dsm_;
  std::filesystem::path scratch_;
  std::vector<Band> bands_;
  int rows_per_band_ = 1;
  size_t spill_heights_ = 0;  // heights a band buffers before appending them to its file
  // MeasureFootprint's occupancy grid, one bit per cell of the extent.
  Eigen::Vector3d first_;
  long long fx0_ = 0, fy0_ = 0, fw_ = 0;
  std::vector<bool> occupied_;
  long occupied_cells_ = 0;
  long points_ = 0;
};

}  // namespace sapmvs

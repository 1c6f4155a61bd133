#include "run/streamed_dsm.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

#include "sapmvs/util/error.h"
#include "sapmvs/util/parallel_for.h"

namespace sapmvs {
namespace {

long long FootprintCell(double v, double origin, double cell) {
  return static_cast<long long>(std::floor((v - origin) / cell));
}

}  // namespace

StreamedDsm::StreamedDsm(const Eigen::Vector3d& first, double xmin, double ymin, double xmax,
                         double ymax, double cell, const std::string& crs, long points,
                         const std::filesystem::path& scratch, long band_heights)
    : dsm_(EmptyDsm(xmin, ymin, xmax, ymax, cell, crs)), scratch_(scratch), first_(first) {
  band_heights = std::max(1L, band_heights);
  const long bands = std::clamp<long>((points + band_heights - 1) / band_heights, 1, dsm_.height);
  spill_heights_ = static_cast<size_t>(std::max(1L, band_heights / 16));
  rows_per_band_ = static_cast<int>((dsm_.height + bands - 1) / bands);
  bands_.resize((dsm_.height + rows_per_band_ - 1) / rows_per_band_);
  fx0_ = FootprintCell(xmin, first.x(), cell);
  fy0_ = FootprintCell(ymin, first.y(), cell);
  fw_ = FootprintCell(xmax, first.x(), cell) - fx0_ + 1;
  const long long fh = FootprintCell(ymax, first.y(), cell) - fy0_ + 1;
  occupied_.assign(static_cast<size_t>(fw_ * fh), false);
}

StreamedDsm::~StreamedDsm() = default;

void StreamedDsm::Spill(Band* band) {
  if (!band->file) band->file = std::make_unique<AtomicFile>(scratch_ / "dsm_band");
  std::ofstream out(band->file->temp_path(), std::ios::binary | std::ios::app);
  out.write(reinterpret_cast<const char*>(band->buffer.data()),
            static_cast<std::streamsize>(band->buffer.size() * sizeof(Height)));
  out.close();
  if (!out) {
    throw Error(band->file->temp_path().string() + ": write failed (" + std::strerror(errno) + ")");
  }
  band->spilled += band->buffer.size();
  band->buffer.clear();
}

void StreamedDsm::Add(PointSpan points) {
  const double cell = dsm_.cell_size;
  for (size_t i = 0; i < points.size; ++i) {
    const Eigen::Vector3d& p = points.data[i].position;
    const size_t index = RasterCellIndex(dsm_, p.x(), p.y());
    Band& band = bands_[index / dsm_.width / rows_per_band_];
    band.buffer.push_back({static_cast<uint32_t>(index), static_cast<float>(p.z())});
    if (band.buffer.size() >= spill_heights_ && bands_.size() > 1) Spill(&band);
    const size_t f = static_cast<size_t>((FootprintCell(p.y(), first_.y(), cell) - fy0_) * fw_ +
                                         FootprintCell(p.x(), first_.x(), cell) - fx0_);
    if (!occupied_[f]) {
      occupied_[f] = true;
      ++occupied_cells_;
    }
    ++points_;
  }
}

GeoRaster StreamedDsm::Finish(int fill_passes) {
  // Two bands at a time: each is one core's read, sort and medians, and
  // their cells are rows of their own.
  ParallelFor(
      static_cast<long>(bands_.size()),
      [&](long k) {
        Band& band = bands_[static_cast<size_t>(k)];
        std::vector<Height> heights(band.spilled);
        std::vector<float> cell_heights;
        if (band.spilled > 0) {
          std::ifstream in(band.file->temp_path(), std::ios::binary);
          in.read(reinterpret_cast<char*>(heights.data()),
                  static_cast<std::streamsize>(band.spilled * sizeof(Height)));
          if (!in) throw Error(band.file->temp_path().string() + ": read failed");
          band.file.reset();
        }
        heights.insert(heights.end(), band.buffer.begin(), band.buffer.end());
        std::vector<Height>().swap(band.buffer);  // `= {}` would keep its capacity
        // By cell; a cell's median does not depend on the order of its heights.
        std::sort(heights.begin(), heights.end(),
                  [](const Height& a, const Height& b) { return a.cell < b.cell; });
        for (size_t i = 0; i < heights.size();) {
          size_t j = i;
          cell_heights.clear();
          while (j < heights.size() && heights[j].cell == heights[i].cell) {
            cell_heights.push_back(heights[j++].z);
          }
          dsm_.values[heights[i].cell] = MedianHeight(&cell_heights);
          i = j;
        }
      },
      1, 2);
  FillDsmGaps(&dsm_, fill_passes);
  return std::move(dsm_);
}

CloudFootprint StreamedDsm::Footprint() const {
  CloudFootprint f;
  f.cell_size = dsm_.cell_size;
  if (points_ == 0) return f;
  f.occupied_cells = occupied_cells_;
  f.area = static_cast<double>(f.occupied_cells) * f.cell_size * f.cell_size;
  f.density = static_cast<double>(points_) / f.area;
  return f;
}

}  // namespace sapmvs

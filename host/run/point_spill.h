#pragma once
// A merged cloud on disk while it is being made: the tiled merge appends each
// tile's points, the statistics and the writers read them back in chunks, so
// the block's points are never in memory at once. A hidden temporary file in
// the run folder (AtomicFile's name: removed when the spill goes, and as a
// stale temporary when a killed run left it).
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <vector>

#include "sapmvs/io/ply_stream.h"
#include "sapmvs/util/atomic_file.h"

namespace sapmvs {

class PointSpill {
 public:
  // Throws sapmvs::Error naming the folder when it cannot be written.
  explicit PointSpill(const std::filesystem::path& dir);
  PointSpill(const PointSpill&) = delete;
  PointSpill& operator=(const PointSpill&) = delete;

  // Throws sapmvs::Error naming the file when a write fails (a full disk).
  void Append(const std::vector<CloudPoint>& points);
  size_t size() const { return size_; }
  // What Read hands out at a time by default: what the writers convert at
  // once (and the merge, which counts their records ahead of them). The LAS
  // writer holds a chunk about five times over (the bytes read, the points,
  // their copy, two record arrays) while GDAL is loaded: at 2^16 points that
  // was 14 MiB at the peak of a run on `small`.
  static constexpr size_t kChunk = 1 << 14;
  // The points in the order appended, `chunk` at a time, from the start at
  // each call. Call after the last Append.
  NextPoints Read(size_t chunk = kChunk);

 private:
  AtomicFile file_;  // never committed: only its temporary name is used
  std::ofstream out_;
  size_t size_ = 0;
};

}  // namespace sapmvs

#pragma once
// A cloud written as PLY in chunks, for clouds that never lie in memory whole
// (a large block's merge, run/tiled_merge.h). The header declares the point
// count and the width of the views field, so the points are seen twice: once
// to fill a PlyCounts, once to write them. WritePly (ply_io.h) is both passes
// over one cloud, so the two give the same bytes.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "sapmvs/io/ply_io.h"

namespace sapmvs {

// What a PLY header declares about its points.
struct PlyCounts {
  size_t count = 0;
  bool views_fit_uchar = true;  // every view count <= 255: stored as uchar, else int
  // Counts `p` as point number `count`. Throws sapmvs::Error naming `file` and
  // the point when it cannot be written: a non-finite coordinate, or (with
  // `has_views`) a negative view count.
  void Add(const std::string& file, const CloudPoint& p, bool has_views);
};

// Consecutive points of a cloud; valid until the next call of the NextPoints
// that gave them.
struct PointSpan {
  const CloudPoint* data = nullptr;
  size_t size = 0;
};
// The next points of a cloud; an empty span at the end.
using NextPoints = std::function<PointSpan()>;

// Writes the points `next` gives as WritePly does, atomically: `format`
// gives the has_* flags and the CRS (its points are not read), `counts` what
// the first pass saw. Throws sapmvs::Error naming `path` when the points
// given are not `counts.count`, or a write fails; nothing is left then.
void WritePlyStream(const std::filesystem::path& path, const PointCloud& format,
                    const PlyCounts& counts, const NextPoints& next);

}  // namespace sapmvs

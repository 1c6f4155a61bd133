#include "sapmvs/run/tiled_merge.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <future>
#include <limits>
#include <optional>

#include "sapmvs/run/core_index.h"
#include "sapmvs/run/seam_leveling.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/parallel_for.h"

namespace sapmvs {
namespace {

struct Box {
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin;
  double xmax = -xmin, ymax = -xmin;
  bool empty() const { return !(xmin <= xmax); }
  void Add(double x, double y) {
    xmin = std::min(xmin, x);
    xmax = std::max(xmax, x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
  }
  bool Meets(const Box& o) const {
    return !empty() && !o.empty() && xmin <= o.xmax && o.xmin <= xmax && ymin <= o.ymax &&
           o.ymin <= ymax;
  }
  bool Holds(double x, double y) const { return x >= xmin && x <= xmax && y >= ymin && y <= ymax; }
};

PointCloud FormatOf(const PointCloud& c) {
  PointCloud f;
  f.crs = c.crs;
  f.has_normals = c.has_normals;
  f.has_colors = c.has_colors;
  f.has_scores = c.has_scores;
  f.has_views = c.has_views;
  return f;
}

// The tile a point belongs to: clamped, so that the extent's far edges
// belong to the last tiles.
int TileOf(double v, double origin, double side, int tiles) {
  if (tiles <= 1) return 0;
  return std::clamp(static_cast<int>(std::floor((v - origin) / side)), 0, tiles - 1);
}

}  // namespace

MergeStats MergeInTiles(const std::vector<MergeSource>& groups, const MergeOptions& options,
                        const MergedTile& emit, MergeLayout* layout_out) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("merge: expected " + problem);
  const size_t n = groups.size();
  MergeStats st;
  st.kept_by_group.assign(n, 0);
  st.core_by_group.assign(n, 0);
  MergeLayout layout;
  // First pass: each group's extent. The clouds are kept while they hold at
  // most tile_points in all, so that a block merged whole reads each group
  // once; past that, one group is in memory at a time.
  std::vector<Box> extent(n);
  Box block;
  // Seams are measured in this first pass and levelled as the tiles load.
  std::optional<SeamLeveling> seams;
  if (options.seam_feather_radii > 0 && n > 1) {
    std::vector<Eigen::Vector2d> centers;
    for (const MergeSource& g : groups) centers.push_back(g.center);
    SeamOptions so;
    so.cell = 2 * options.radius;
    so.band = options.seam_band_radii * options.radius;
    so.feather = options.seam_feather_radii * options.radius;
    // Two radii: groups that disagree by their orientations differ by a
    // fraction of a pixel (the Caliterra flight's stretches: a median 1.4
    // cm at 6.9 cm GSD).
    so.max_offset = 2 * options.radius;
    seams.emplace(std::move(centers), so);
  }
  std::vector<PointCloud> read(n);
  bool all_read = true;
  for (size_t g = 0; g < n; ++g) {
    long count = 0;
    PointCloud c = groups[g].load([&](const Eigen::Vector3d& p) {
      extent[g].Add(p.x(), p.y());
      if (seams) seams->Add(static_cast<int>(g), p);
      ++count;
      return all_read && layout.input_points + count <= options.tile_points;
    });
    if (g == 0) layout.format = FormatOf(c);
    layout.input_points += count;
    if (!extent[g].empty()) {
      block.Add(extent[g].xmin, extent[g].ymin);
      block.Add(extent[g].xmax, extent[g].ymax);
    }
    if (all_read && layout.input_points <= options.tile_points) {
      read[g] = std::move(c);
    } else if (all_read) {
      all_read = false;
      read = std::vector<PointCloud>(n);
    }
  }
  if (seams) {
    seams->Finish();
    st.seam_pairs = seams->pairs();
    st.seam_offset = seams->median_offset();
    if (seams->pairs() == 0) seams.reset();
  }
  if (layout.input_points == 0) {
    if (layout_out) *layout_out = layout;
    return st;
  }
  // In the radii a point outside its core is judged by, and at least twice
  // the reach of the cylinder along its normal (cloud_merge.h).
  const double halo = options.radius * std::max(options.halo_radii * options.outside_core_radii,
                                                2 * std::hypot(options.outside_core_radii,
                                                               options.surface_depth_radii));
  layout.tiles_x = layout.tiles_y = 1;
  if (layout.input_points > options.tile_points) {
    // Square tiles of about tile_points each at the block's mean density,
    // and at least four halos wide, so that the halos cost at most about
    // twice the tile's own points.
    const double w = std::max(block.xmax - block.xmin, options.radius);
    const double h = std::max(block.ymax - block.ymin, options.radius);
    const double share = static_cast<double>(options.tile_points) / layout.input_points;
    layout.tile_side = std::max(std::sqrt(w * h * share), 4 * halo);
    layout.tiles_x = std::max(1, static_cast<int>(std::ceil(w / layout.tile_side)));
    layout.tiles_y = std::max(1, static_cast<int>(std::ceil(h / layout.tile_side)));
    if (layout.tiles() == 1) layout.tile_side = 0;
  }
  if (layout_out) *layout_out = layout;
  const bool whole = layout.tiles() == 1;

  std::vector<Eigen::Vector2d> centers(n);
  for (size_t g = 0; g < n; ++g) centers[g] = groups[g].center;
  // Once for all tiles: over the block's extent, a grid cell per quarter of
  // a group's ground.
  const CoreIndex cores(std::move(centers), options.BorderReach(), {block.xmin, block.ymin},
                        {block.xmax, block.ymax});
  struct TileOut {
    PointCloud points;
    long input = 0, band_outliers = 0;
    std::vector<long> kept_by_group, core_by_group;
  };
  auto merge_tile = [&](int tx, int ty) {
    Box reach = block;  // the tile and its halo
    if (!whole) {
      reach.xmin = block.xmin + tx * layout.tile_side - halo;
      reach.xmax = block.xmin + (tx + 1) * layout.tile_side + halo;
      reach.ymin = block.ymin + ty * layout.tile_side - halo;
      reach.ymax = block.ymin + (ty + 1) * layout.tile_side + halo;
    }
    auto own = [&](const CloudPoint& p) {
      return whole || (TileOf(p.position.x(), block.xmin, layout.tile_side, layout.tiles_x) == tx &&
                       TileOf(p.position.y(), block.ymin, layout.tile_side, layout.tiles_y) == ty);
    };
    std::vector<PointCloud> clouds(n);
    std::vector<GroupCloud> parts(n);
    for (size_t g = 0; g < n; ++g) {
      parts[g].cloud = &clouds[g];
      parts[g].center = groups[g].center;
    }
    // The groups' clouds of a tile are read side by side: reading and
    // parsing a checkpoint is one core's work, and a tile holds all its
    // groups' points at once whichever order they come in.
    ParallelFor(
        static_cast<long>(n),
        [&](long g) {
          if (!extent[g].Meets(reach)) return;
          if (whole) {
            clouds[g] = all_read ? std::move(read[g]) : groups[g].load(PointFilter());
          } else {
            clouds[g] =
                groups[g].load([&](const Eigen::Vector3d& p) { return reach.Holds(p.x(), p.y()); });
          }
          if (seams) {
            for (CloudPoint& p : clouds[g].points) {
              p.position.z() += seams->Correction(static_cast<int>(g), p.position);
            }
          }
        },
        1);
    TileOut out;
    out.kept_by_group.assign(n, 0);
    out.core_by_group.assign(n, 0);
    MergeStats tile_stats;
    std::vector<MergedRef> band_outliers;
    std::vector<MergedRef> refs =
        MergeGroupRefs(parts, options, &tile_stats, &cores, &band_outliers);
    for (const MergedRef& ref : band_outliers) {
      out.band_outliers += own(clouds[ref.group].points[ref.index]);
    }
    out.points = layout.format;
    out.points.points.reserve(
        static_cast<size_t>(std::count_if(refs.begin(), refs.end(), [&](const MergedRef& ref) {
          return own(clouds[ref.group].points[ref.index]);
        })));
    for (const MergedRef& ref : refs) {
      const CloudPoint& p = clouds[ref.group].points[ref.index];
      if (!own(p)) continue;
      out.points.points.push_back(p);
      ++out.kept_by_group[ref.group];
      if (ref.core) ++out.core_by_group[ref.group];
    }
    for (const PointCloud& c : clouds) {
      for (const CloudPoint& p : c.points) out.input += own(p);
    }
    return out;
  };
  // Two tiles are read and merged at once (the greedy pass of one beside
  // the reading of the other: one at a time, the Caliterra flight's merge
  // kept 1.4 of 2 cores busy), and the caller's work on a tile (its
  // outputs: one core's) runs beside them; tiles are handed over in order.
  std::vector<std::pair<int, int>> order;
  for (int ty = 0; ty < layout.tiles_y; ++ty) {
    for (int tx = 0; tx < layout.tiles_x; ++tx) order.emplace_back(tx, ty);
  }
  constexpr size_t kTilesAtOnce = 2;
  std::deque<std::future<TileOut>> merging;
  size_t launched = 0;
  auto launch = [&] {
    const auto [tx, ty] = order[launched++];
    merging.push_back(std::async(std::launch::async, merge_tile, tx, ty));
  };
  std::future<void> emitting;
  // Waits for what runs, so that nothing outlives the frame on an exception.
  auto drain = [&] {
    for (auto& f : merging) {
      if (f.valid()) f.wait();
    }
    if (emitting.valid()) emitting.wait();
  };
  try {
    while (launched < order.size() && merging.size() < kTilesAtOnce) launch();
    while (!merging.empty()) {
      TileOut tile = merging.front().get();
      merging.pop_front();
      if (launched < order.size()) launch();
      st.input += tile.input;
      st.kept += static_cast<long>(tile.points.points.size());
      st.duplicates +=
          tile.input - static_cast<long>(tile.points.points.size()) - tile.band_outliers;
      st.band_outliers += tile.band_outliers;
      for (size_t g = 0; g < n; ++g) {
        st.kept_by_group[g] += tile.kept_by_group[g];
        st.core_by_group[g] += tile.core_by_group[g];
      }
      if (tile.points.points.empty()) continue;
      if (emitting.valid()) emitting.get();
      emitting = std::async(std::launch::async, [&emit, &layout, done = std::move(tile.points)] {
        emit(done, layout);
      });
    }
  } catch (...) {
    drain();
    throw;
  }
  if (emitting.valid()) emitting.get();
  return st;
}

}  // namespace sapmvs

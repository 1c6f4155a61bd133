#pragma once
// The merge of a block's group clouds (cloud_merge.h) tile by tile, so that
// a block of any size merges with a bounded part of its points in memory.
//
// The block's XY extent is cut into square tiles holding about
// MergeOptions::tile_points group points each. A tile loads the groups whose
// points reach the tile or its halo (MergeOptions::halo_radii merge radii
// wide), runs the same greedy merge on their points inside tile and halo,
// with every group's centre taking part in the cores, and keeps the kept
// points inside the tile; each point belongs to exactly one tile.
//
// Why that is the global merge: the global merge decides a point p by the
// points kept before it (core first, then by score) from other groups
// within the radius r. Those are decided the same way, so p's fate depends
// on a chain of points, each within r of the next and earlier in the order.
// The tile's merge sees every point within the halo h = halo_radii * r of
// the tile, so it decides p exactly unless such a chain from p leaves the
// halo: at least h / r links, each a point dropped or kept because of the
// next. On matched surfaces a point has one or two duplicates of other groups
// near it, and chains of alternating keep/drop decisions longer than a few
// links are rare; where one crosses the halo, a point near the tile border
// may be kept that the global merge drops, or the other way, and two tiles'
// kept points may then be a duplicate pair across the border. The unit test
// (tiled_merge_test.cc) bounds the difference on a synthetic multi-tile
// block; on `small` cut into tiles it is measured in docs/running.md. A block that
// fits in one tile is merged exactly as MergeGroupClouds merges it, and
// comes out in the same order: byte-identical outputs.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "sapmvs/io/ply_io.h"
#include "sapmvs/run/cloud_merge.h"

namespace sapmvs {

// One group of the block: its cloud, read when a tile needs it (a group's
// checkpoint), and its ground centre (world XY), as in GroupCloud. `load`
// returns the points `keep` accepts (all when it is empty), in the cloud's
// order, with the cloud's crs and has_* flags, showing `keep` every point:
// a tile then holds its share of a group, never the whole.
struct MergeSource {
  std::function<PointCloud(const PointFilter& keep)> load;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
};

// What the tiled merge found before the first tile: the whole block's input.
struct MergeLayout {
  int tiles_x = 0, tiles_y = 0;  // 1 x 1 for a block merged whole
  double tile_side = 0;          // CRS units; 0 for one tile
  long input_points = 0;         // of all groups
  PointCloud format;             // crs and has_* flags of the group clouds, no points
  int tiles() const { return tiles_x * tiles_y; }
};

// Kept points of one tile, in the merge's order (group, then index), with the
// layout; called once per tile that keeps points, tiles row by row, one call
// at a time, on a thread of its own while the next tile is merged.
using MergedTile = std::function<void(const PointCloud& tile, const MergeLayout& layout)>;

// Merges `groups` tile by tile, reading each group once to find its extent and
// then once per tile it reaches, and hands each tile's kept points to `emit`.
// With options.seam_feather_radii > 0 the first read also measures the
// seams between the groups, and every group's points are levelled
// (seam_leveling.h) as a tile loads them, before they are merged; the
// heights then differ from MergeGroupClouds'.
// The stats count each point once, in the tile it lies in. Throws
// sapmvs::Error for bad options, or what `load` throws.
MergeStats MergeInTiles(const std::vector<MergeSource>& groups, const MergeOptions& options,
                        const MergedTile& emit, MergeLayout* layout = nullptr);

}  // namespace sapmvs

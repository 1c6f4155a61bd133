// The tiled merge (tiled_merge.h) against the global one (cloud_merge.h), and
// the chunked writers and DSM that carry its output: one tile is the global
// merge exactly; several differ only near tile borders; chunks give the
// bytes of one piece.
#include "sapmvs/run/tiled_merge.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "run/streamed_dsm.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_stream.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/run/cloud_las.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::ScratchDir;
using test::Slurp;

// A 3 x 3 block of groups, each matching a 60 m square around its centre
// (40 m apart, so neighbours overlap by 20 m) with 0.5 m points jittered
// off the grid, on gentle relief, scores random: the cross-group duplicates
// the merge resolves, across every tile border.
struct GroupGrid {
  std::vector<PointCloud> clouds;
  std::vector<Eigen::Vector2d> centers;
};

GroupGrid MakeGroupGrid() {
  GroupGrid b;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2), score(0.5, 1.0);
  for (int gy = 0; gy < 3; ++gy) {
    for (int gx = 0; gx < 3; ++gx) {
      const Eigen::Vector2d c(500000.0 + 40 * gx, 5400000.0 + 40 * gy);
      PointCloud cloud;
      cloud.has_scores = cloud.has_normals = cloud.has_colors = cloud.has_views = true;
      cloud.crs = "EPSG:32633";
      for (double y = -30; y < 30; y += 0.5) {
        for (double x = -30; x < 30; x += 0.5) {
          CloudPoint p;
          const double px = c.x() + x + jitter(rng), py = c.y() + y + jitter(rng);
          p.position = {px, py, 300 + 2 * std::sin(px / 15) + std::cos(py / 11)};
          p.normal = {0, 0, 1};
          p.color = {static_cast<uint8_t>(gx * 80), static_cast<uint8_t>(gy * 80), 7};
          p.score = static_cast<float>(score(rng));
          p.num_views = 3 + gx;
          cloud.points.push_back(p);
        }
      }
      b.clouds.push_back(cloud);
      b.centers.push_back(c);
    }
  }
  return b;
}

std::vector<MergeSource> Sources(const GroupGrid& b) {
  std::vector<MergeSource> s;
  for (size_t g = 0; g < b.clouds.size(); ++g) {
    s.push_back({[&b, g](const PointFilter& keep) {
                   PointCloud c = b.clouds[g];
                   if (keep) {
                     auto& p = c.points;
                     p.erase(std::remove_if(p.begin(), p.end(),
                                            [&](const CloudPoint& q) { return !keep(q.position); }),
                             p.end());
                   }
                   return c;
                 },
                 b.centers[g]});
  }
  return s;
}

PointCloud GlobalMerge(const GroupGrid& b, const MergeOptions& o, MergeStats* st) {
  std::vector<GroupCloud> parts;
  for (size_t g = 0; g < b.clouds.size(); ++g) parts.push_back({&b.clouds[g], b.centers[g]});
  return MergeGroupClouds(parts, o, st);
}

PointCloud TiledMerge(const GroupGrid& b, const MergeOptions& o, MergeStats* st,
                      MergeLayout* layout) {
  PointCloud all;
  *st = MergeInTiles(
      Sources(b), o,
      [&](const PointCloud& tile, const MergeLayout&) {
        if (all.points.empty())
          all = tile;
        else
          all.points.insert(all.points.end(), tile.points.begin(), tile.points.end());
      },
      layout);
  return all;
}

using Key = std::tuple<double, double, double>;
std::set<Key> Keys(const PointCloud& c) {
  std::set<Key> k;
  for (const CloudPoint& p : c.points) k.insert({p.position.x(), p.position.y(), p.position.z()});
  return k;
}

TEST(TiledMergeTest, OneTileIsTheGlobalMerge) {
  const GroupGrid b = MakeGroupGrid();
  MergeOptions o;
  o.radius = 0.5;
  o.tile_points = 1000000;  // more than the block's 129,600
  MergeStats global_stats, tiled_stats;
  MergeLayout layout;
  const PointCloud global = GlobalMerge(b, o, &global_stats);
  const PointCloud tiled = TiledMerge(b, o, &tiled_stats, &layout);
  EXPECT_EQ(layout.tiles(), 1);
  ASSERT_EQ(tiled.points.size(), global.points.size());
  for (size_t i = 0; i < global.points.size(); ++i) {
    ASSERT_EQ(tiled.points[i].position, global.points[i].position) << "point " << i;
  }
  EXPECT_EQ(tiled_stats.input, global_stats.input);
  EXPECT_EQ(tiled_stats.duplicates, global_stats.duplicates);
  EXPECT_EQ(tiled_stats.kept_by_group, global_stats.kept_by_group);
  EXPECT_EQ(tiled_stats.core_by_group, global_stats.core_by_group);
  EXPECT_EQ(tiled.crs, global.crs);
  EXPECT_TRUE(tiled.has_views && tiled.has_normals && tiled.has_colors && tiled.has_scores);
}

TEST(TiledMergeTest, ManyTilesDifferOnlyNearBorders) {
  const GroupGrid b = MakeGroupGrid();
  MergeOptions o;
  o.radius = 0.5;
  o.tile_points = 8000;  // tiles of about 15 m: dozens, every group cut
  // A halo of 8 radii, as measured below, for the points outside their
  // cores that are judged at 3.
  o.outside_core_radii = 3;
  o.halo_radii = 8.0 / 3;
  // A cylinder along the normals that this halo covers twice (the default's
  // would widen the halo, and the tiles with it).
  o.surface_depth_radii = 2;
  MergeStats global_stats, tiled_stats;
  MergeLayout layout;
  const PointCloud global = GlobalMerge(b, o, &global_stats);
  const PointCloud tiled = TiledMerge(b, o, &tiled_stats, &layout);
  EXPECT_GE(layout.tiles(), 25);
  EXPECT_EQ(tiled_stats.input, global_stats.input);  // each point counted once
  EXPECT_EQ(tiled_stats.kept, static_cast<long>(tiled.points.size()));
  const std::set<Key> g = Keys(global), t = Keys(tiled);
  EXPECT_EQ(t.size(), tiled.points.size()) << "a point kept by two tiles";
  std::vector<Key> only_tiled, only_global;
  std::set_difference(t.begin(), t.end(), g.begin(), g.end(), std::back_inserter(only_tiled));
  std::set_difference(g.begin(), g.end(), t.begin(), t.end(), std::back_inserter(only_global));
  // Measured: no point differs either way, with the default halo of 8 radii
  // and even with 1. The bound leaves room for chains across a halo, not for
  // tiles merged without one (several % of the points lie within a radius
  // of a tile border here).
  const double n = static_cast<double>(global.points.size());
  EXPECT_LE(only_tiled.size() / n, 0.001) << only_tiled.size() << " of " << n;
  EXPECT_LE(only_global.size() / n, 0.001) << only_global.size() << " of " << n;
}

TEST(TiledMergeTest, ChunkedWritersGiveTheBytesOfOnePiece) {
  const GroupGrid b = MakeGroupGrid();
  const PointCloud& cloud = b.clouds[4];
  const std::filesystem::path dir = ScratchDir();
  WritePly(dir / "whole.ply", cloud);
  PlyCounts counts;
  for (const CloudPoint& p : cloud.points) counts.Add("x", p, cloud.has_views);
  size_t at = 0;
  const size_t step = 997;  // chunks that end anywhere
  WritePlyStream(dir / "chunks.ply", cloud, counts, [&] {
    const PointSpan s{cloud.points.data() + at, std::min(step, cloud.points.size() - at)};
    at += s.size;
    return s;
  });
  EXPECT_EQ(Slurp(dir / "chunks.ply"), Slurp(dir / "whole.ply"));

  LasWriteOptions lo;
  lo.crs = cloud.crs;
  lo.creation_day = 1;
  lo.creation_year = 2024;
  WriteCloudLas(dir / "whole.las", cloud, lo);
  LasCounts las_counts;
  std::vector<LasExtraField> ranges;
  std::vector<PointCloud> chunks;
  for (size_t first = 0; first < cloud.points.size(); first += step) {
    PointCloud c = cloud;
    c.points.assign(cloud.points.begin() + first,
                    cloud.points.begin() + std::min(first + step, cloud.points.size()));
    for (const PointRecord& r : ToLasRecords(c)) las_counts.Add("x", r, lo.version);
    WidenExtraRanges("x", ToLasExtras(c), c.points.size(), &ranges);
    chunks.push_back(c);
  }
  size_t k = 0;
  std::vector<PointRecord> records;
  std::vector<LasExtraField> extras;
  WriteLasStream(dir / "chunks.las", las_counts, lo, ranges,
                 [&](const std::vector<PointRecord>** r, const std::vector<LasExtraField>** e) {
                   if (k == chunks.size()) return false;
                   records = ToLasRecords(chunks[k]);
                   extras = ToLasExtras(chunks[k++]);
                   *r = &records;
                   *e = &extras;
                   return true;
                 });
  EXPECT_EQ(Slurp(dir / "chunks.las"), Slurp(dir / "whole.las"));

  // Fewer points than declared: refused, and nothing left.
  counts.count += 1;
  at = 0;
  EXPECT_THROW(
      WritePlyStream(
          dir / "short.ply", cloud, counts,
          [&] {
            const PointSpan s{cloud.points.data() + at, std::min(step, cloud.points.size() - at)};
            at += s.size;
            return s;
          }),
      Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "short.ply"));
}

TEST(TiledMergeTest, BandedDsmIsTheWholeDsm) {
  const GroupGrid b = MakeGroupGrid();
  std::vector<GroupCloud> parts;
  for (size_t g = 0; g < b.clouds.size(); ++g) parts.push_back({&b.clouds[g], b.centers[g]});
  MergeOptions mo;
  mo.radius = 0.5;
  const PointCloud cloud = MergeGroupClouds(parts, mo);
  DsmOptions o;
  o.cell_size = 1.5;
  o.fill_passes = 2;
  double cell = 0;
  const GeoRaster whole = RasterizeDsm(cloud, o, &cell);
  const CloudFootprint fp = MeasureFootprint(cloud, cell);
  Eigen::Vector3d lo = cloud.points.front().position, hi = lo;
  for (const CloudPoint& p : cloud.points) {
    lo = lo.cwiseMin(p.position);
    hi = hi.cwiseMax(p.position);
  }
  const std::filesystem::path dir = ScratchDir();
  // Bands of 5,000 heights: about 20 bands, each spilled to its file.
  StreamedDsm banded(cloud.points.front().position, lo.x(), lo.y(), hi.x(), hi.y(), cell, cloud.crs,
                     static_cast<long>(cloud.points.size()), dir, 5000);
  for (size_t first = 0; first < cloud.points.size(); first += 4096) {
    banded.Add({cloud.points.data() + first, std::min<size_t>(4096, cloud.points.size() - first)});
  }
  const CloudFootprint banded_fp = banded.Footprint();
  const GeoRaster r = banded.Finish(o.fill_passes);
  EXPECT_EQ(banded_fp.occupied_cells, fp.occupied_cells);
  EXPECT_EQ(banded_fp.density, fp.density);
  ASSERT_EQ(r.width, whole.width);
  ASSERT_EQ(r.height, whole.height);
  EXPECT_EQ(r.origin_x, whole.origin_x);
  EXPECT_EQ(r.origin_y, whole.origin_y);
  long differ = 0;
  for (size_t i = 0; i < r.values.size(); ++i) {
    const float a = r.values[i], w = whole.values[i];
    differ += !((std::isnan(a) && std::isnan(w)) || a == w);
  }
  EXPECT_EQ(differ, 0);
  // The band files are gone with the DSM.
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
}  // namespace sapmvs

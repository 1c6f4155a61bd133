#pragma once
// Merging the clouds of overlapping image groups into one cloud that holds
// each surface point once (method.md 5.1; the paper keeps the union and does
// not say how duplicates go).
//
// Each group owns a core: the XY points nearer to its ground centre than to
// any other group's (a Voronoi cell). Points are taken core points first,
// then by score, best first; a point within blend_radii of its core's
// border is always kept; a core point is dropped when a point already
// kept from another group lies within `radius` of it (3D), a point outside
// its group's core when one lies within outside_core_radii radii, or within
// that of the line along its normal and surface_depth_radii along it. Points of
// one group are never dropped for each other, so a group's own density stays
// as matched; a point outside its group's core survives only where the owner
// matched nothing nearby, so group borders get neither seams nor holes, and
// the owner's surface is not doubled by another group's a little off it.

#include <Eigen/Core>
#include <algorithm>
#include <utility>
#include <vector>

#include "sapmvs/io/ply_io.h"

namespace sapmvs {

class CoreIndex;

struct GroupCloud {
  const PointCloud* cloud = nullptr;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // world XY of the group's ground centre
};

struct MergeOptions {
  // Duplicate distance, CRS units (> 0): the caller passes about one ground
  // sample distance of the level matched, the spacing of the emitted points.
  double radius = 0;
  // A point outside its group's core is a duplicate of another group's
  // point within this many radii (>= 1). With real orientations two groups
  // place a surface a few centimetres apart: at 1 radius the other group's
  // points between the owner's survived and stacked a second layer on its
  // surface, which doubled the merged cloud's local noise.
  double outside_core_radii = 3;
  // A point outside its group's core is also a duplicate of another group's
  // point within outside_core_radii of the line along its normal and within
  // this many radii along it (>= 0; points without normals: the sphere
  // alone). The other group matched that piece of surface, placed higher or
  // lower (a crown, a hedge): on the Caliterra flight the sphere alone left
  // such second layers in the margin each group matches beyond its core,
  // and neighbouring DSM cells 2 to 5 cells inside a group's border differed
  // by a p90 of 10.1 cm against 9.5 cm further in; with 10 radii, 9.5 cm.
  double surface_depth_radii = 10;
  // Points within this many radii of their core's border are never
  // duplicates (>= 0): two groups a little apart there would otherwise meet
  // in a step, each group's cells correlated through its own patches and the
  // two independent; with both kept, the cells by the border hold both
  // surfaces.
  double blend_radii = 0;
  // Within this many radii of a border (>= 0; 0 = off), a point whose
  // column (the kept points of every group within vote_column_radii across
  // and vote_reach_depths * surface_depth_radii up or down) has its median
  // height more than surface_depth_radii from the point's is dropped. Only
  // points whose normal lies within 60 degrees of vertical (or is unknown)
  // vote; a steeper point is judged only where they outnumber the steep
  // ones three to one (a wrong match on open ground, not a wall). Each
  // group matches the margin beyond its core least well: on the Caliterra
  // flight both groups' margins by a border held clusters of wrong matches
  // a metre or two under the ground, which the blend band keeps and the
  // duplicate test cannot see (the other group's surface lies beyond
  // surface_depth_radii). With the vote 1,148 of its 3.0 million points go,
  // and the p99 of the DSM's steps across borders falls from 0.48 to 0.41 m
  // (0.29 m inside groups; what is left is mostly a forest edge that runs
  // along a border). Layers further apart than the reach (a crown over the
  // ground) do not vote against each other.
  double vote_zone_radii = 40;
  double vote_column_radii = 3;
  double vote_reach_depths = 6;
  // The tiled merge (tiled_merge.h): about this many group points per tile;
  // a block with no more than these is merged in one piece (>= 1000).
  long tile_points = 250000;  // RunOptions::merge_tile_points gives it
  // The tiled merge levels the seams between groups before it merges them
  // (seam_leveling.h): each group's heights meet its neighbour's at their
  // border and fade to its own over this many radii. 0 = off.
  double seam_feather_radii = 0;
  // The heights of two groups are compared within this many radii of their
  // border, where both matched (> 0).
  double seam_band_radii = 4;
  // The tiled merge's halo: each tile is merged with the points within this
  // many times radius * outside_core_radii around it, and keeps only its own
  // (>= 1).
  double halo_radii = 8;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
  // How far from a border the merge must know a point's distance to it.
  double BorderReach() const {
    return radius *
           std::max(blend_radii, vote_zone_radii > 0 ? vote_zone_radii + vote_column_radii : 0.0);
  }
};

struct MergeStats {
  long input = 0;
  long kept = 0;
  long duplicates = 0;              // dropped: another group's point within radius
  long band_outliers = 0;           // dropped: off their column's height by a border
  std::vector<long> kept_by_group;  // in the order of the groups given
  std::vector<long> core_by_group;  // of those, inside the group's own core
  // The tiled merge's seam levelling: borders measured, and the median
  // |offset| of the stretches levelled (CRS units).
  int seam_pairs = 0;
  double seam_offset = 0;
};

// The merged cloud takes crs and the has_* flags from the first group (all
// groups of one run agree). Deterministic: the same inputs give the same
// points in the same order. Throws sapmvs::Error for bad options.
PointCloud MergeGroupClouds(const std::vector<GroupCloud>& groups, const MergeOptions& options,
                            MergeStats* stats = nullptr);

// A point the merge keeps: groups[group].cloud->points[index], and whether it
// lies in its group's core.
struct MergedRef {
  int group = 0;
  size_t index = 0;
  bool core = false;
};

// What MergeGroupClouds keeps, in its output order (group, then index). A
// group's cloud may hold only some of its points (a tile of the block, see
// tiled_merge.h): every group's centre still takes part in the cores.
// `cores`, the groups' centres indexed with options.BorderReach() as their
// reach, saves a caller that merges many tiles building it for each
// (CoreIndex); without, it is built from the groups' centres.
// `band_outliers`, if given, receives the points the vote by the borders
// (vote_zone_radii) dropped (MergeStats::band_outliers counts them).
std::vector<MergedRef> MergeGroupRefs(const std::vector<GroupCloud>& groups,
                                      const MergeOptions& options, MergeStats* stats = nullptr,
                                      const CoreIndex* cores = nullptr,
                                      std::vector<MergedRef>* band_outliers = nullptr);

// The index of the centre nearest to (x, y): the core owner; -1 for none.
int CoreOwner(const std::vector<Eigen::Vector2d>& centers, double x, double y);

// Signed distance from p to the bisector of centres a and b, the border of
// their cores: positive on a's side; infinite when a and b coincide.
double BeyondBisector(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p);

// The core owner of (x, y) and the distance from it to the owner's core
// border (infinite with one centre); owner -1 for no centre.
std::pair<int, double> CoreOwnerAndBorder(const std::vector<Eigen::Vector2d>& centers, double x,
                                          double y);

// Pairs of points of different groups (group_of[i] is point i's group) within
// `radius` of each other (3D): what the merge leaves none of. radius > 0.
long CountCrossGroupPairs(const PointCloud& cloud, const std::vector<int>& group_of, double radius);

// How many points of `from` have a point of `to` within `radius` (3D): one
// cloud's coverage of another, as profiling/versus_pmvs2 compares clouds of
// different matchers. radius > 0. `has`, if given, receives the answer per
// point of `from`.
long CountWithNeighbour(const PointCloud& from, const PointCloud& to, double radius,
                        std::vector<bool>* has = nullptr);

// How many points of `from` lie within `tolerance` of the tangent plane
// (position and normal) of some point of `to` that is within `reach` (3D).
// A cloud denser than `to` has points between `to`'s samples, farther than
// `tolerance` from each of them yet on the surface they sample; this counts
// those as on it, and points beyond `reach` of every sample as off it.
// `to` needs normals; 0 < tolerance <= reach.
long CountNearSurface(const PointCloud& from, const PointCloud& to, double tolerance, double reach);

}  // namespace sapmvs

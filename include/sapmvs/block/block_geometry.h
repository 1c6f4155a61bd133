#pragma once
// What a block's geometry says about its scene before any matching: where each
// image's optical axis meets the surface, its ground sample distance there,
// its footprint, the flying height and the ground extent. `sapmvs info`
// prints it; grouping and matching use the depths.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"
#include "sapmvs/block/tie_points.h"

namespace sapmvs {

// Where the scene surface came from, best first.
// Tie points (tie_points.h) are derived when a block brings none of the others.
enum class SurfaceSource { kDem, kSparsePoints, kGroundHeight, kTiePoints, kNone };
std::string ToString(SurfaceSource source);

struct ImageGeometry {
  bool valid = false;           // false when no surface estimate reaches this image
  bool looks_down = false;      // optical axis within 60 deg of nadir (world -Z)
  Eigen::Vector3d scene_point;  // surface point on the optical axis
  double depth = 0;             // its depth, block units
  double gsd = 0;               // pixel footprint there: on the ground when looking down,
                                // else on a plane facing the camera (block units)
  double height_above = 0;      // camera Z minus scene Z
  std::array<Eigen::Vector3d, 4> footprint;  // image corners on the surface
};

struct BlockGeometry {
  SurfaceSource source = SurfaceSource::kNone;
  std::vector<ImageGeometry> images;  // one per block image
  int num_valid = 0;
  bool aerial = false;  // most images look down
  double gsd_min = 0, gsd_max = 0, gsd_median = 0;
  double flying_height = 0;  // mean height above the scene (aerial blocks)
  Eigen::Vector3d extent_min = Eigen::Vector3d::Zero();  // bounding box of the footprints
  Eigen::Vector3d extent_max = Eigen::Vector3d::Zero();
  std::vector<TiePoint> tie_points;  // derived when the block has no other source
};

// Estimates the scene surface from the best source the block offers.
BlockGeometry EstimateBlockGeometry(const Block& block);

// Empty when some image has a surface estimate (and so a GSD). Otherwise one
// line saying why none has, naming the block, the surface source and the
// images: matching, merging and tiling all need a GSD, so commands fail with
// this up front instead of with a zero radius after the work.
std::string NoSurfaceReason(const Block& block, const BlockGeometry& geometry);

}  // namespace sapmvs

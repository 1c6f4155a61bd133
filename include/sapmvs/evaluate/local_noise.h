#pragma once
// Comparing clouds without ground truth: how rough a cloud is locally, and
// how much ground it covers. Both are comparable across matchers that
// sample the surface at different densities.
//   local noise   for random points, the distance from the point to the
//                 plane fitted (PCA) to random neighbours within a horizontal
//                 radius; two surfaces a few centimetres apart, stacked,
//                 double it where one alone is smooth;
//   ground cover  the cells of a square grid holding at least one point.
#include <Eigen/Core>
#include <cstdint>
#include <set>
#include <utility>

#include "sapmvs/io/ply_io.h"

namespace sapmvs {

struct LocalNoiseOptions {
  // Points sampled (all when the cloud has fewer), with this seed.
  long samples = 40000;
  uint32_t seed = 1;
  // Horizontal radius of the neighbourhood, CRS units (> 0): 4 GSD of the
  // level matched, where PMVS2's samples 2 GSD apart give about 12.
  double radius = 0;
  // Neighbours the plane is fitted to, drawn at random from those within
  // the radius; a point with fewer than min_neighbours is not sampled.
  int neighbours = 12;
  int min_neighbours = 6;
  std::string Problem() const;
};

struct LocalNoise {
  long sampled = 0;  // points with enough neighbours
  double median = 0;
  double p90 = 0;
};

// Throws Error for bad options.
LocalNoise MeasureLocalNoise(const PointCloud& cloud, const LocalNoiseOptions& options);

// The cells (cell x, cell y) of side `cell` (> 0, CRS units) that hold a
// point of `cloud`: count one cloud's with size(), and a union or an
// intersection of several with std::set's algorithms.
std::set<std::pair<int64_t, int64_t>> CoveredCells(const PointCloud& cloud, double cell);

}  // namespace sapmvs

#pragma once
// The groups' cores (the Voronoi cells of their centres) as a grid of
// candidate centres. The merge asks every point which core it lies in and
// how far it is from that core's border; against every centre, that cost
// points x groups, and the merge's time grew with the groups as much as
// with the points. A grid cell lists the centres that can be the nearest
// to a point in it, or whose border with the nearest lies within `reach`:
// a centre g further than |p - own| + 2 reach from p is neither, as the
// border of own and g lies at least (|p - g| - |p - own|) / 2 beyond p.
#include <Eigen/Core>
#include <utility>
#include <vector>

namespace sapmvs {

class CoreIndex {
 public:
  // `centers` (world XY); borders within `reach` (>= 0) of a point are
  // found exactly; the grid covers [lo, hi], and a point outside it is
  // compared with every centre.
  CoreIndex(std::vector<Eigen::Vector2d> centers, double reach, const Eigen::Vector2d& lo,
            const Eigen::Vector2d& hi);
  // The same over the centres' bounding box grown by twice the largest
  // distance from a centre to its nearest neighbour, and by 2 reach.
  CoreIndex(std::vector<Eigen::Vector2d> centers, double reach);

  // The index of the centre nearest to p (CoreOwner); -1 with no centre.
  int Owner(const Eigen::Vector2d& p) const;
  // The owner, and the distance from p to its core's border
  // (CoreOwnerAndBorder) where that is within reach; otherwise a distance
  // larger than reach (infinite with one centre).
  std::pair<int, double> OwnerAndBorder(const Eigen::Vector2d& p) const;
  // The nearest centre and the next nearest, where the border of the two
  // lies within reach of p; otherwise some centre whose border with the
  // nearest lies further than reach (-1 with fewer than two centres).
  std::pair<int, int> TwoNearest(const Eigen::Vector2d& p) const;

  const std::vector<Eigen::Vector2d>& centers() const { return centers_; }

 private:
  const std::vector<int>& Candidates(const Eigen::Vector2d& p) const;
  void Build(double reach, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi);

  std::vector<Eigen::Vector2d> centers_;
  std::vector<int> all_;
  Eigen::Vector2d lo_ = Eigen::Vector2d::Zero();
  double side_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> cells_;  // row-major, nx_ x ny_
};

}  // namespace sapmvs

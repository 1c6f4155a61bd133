#pragma once
// The ground a group owns (the paper's groups: each matches its own part of
// the block, and the images around it serve as views). A group's region is
// the Voronoi cell of its ground centre among all groups' centres, widened
// by a margin so that neighbouring groups overlap enough to meet without a
// gap. A group that matched all it saw matched most of its neighbours'
// ground as well, and the merge then kept two slightly different surfaces
// where orientations are not exact, or dropped one as duplicates.
#include <Eigen/Core>
#include <vector>

namespace sapmvs {

class GroundRegion {
 public:
  // Everything: the region of a block matched as one group.
  GroundRegion() = default;
  // The cell of centers[own] among `centers` (world XY), widened by
  // `margin` (world units, >= 0). Centres equal to centers[own] are skipped.
  GroundRegion(const std::vector<Eigen::Vector2d>& centers, int own, double margin);

  // Whether world XY `xy` lies in the region.
  bool Contains(const Eigen::Vector2d& xy) const {
    for (const HalfPlane& h : half_planes_) {
      if (h.normal.dot(xy) > h.offset) return false;
    }
    return true;
  }
  bool Unbounded() const { return half_planes_.empty(); }
  // The region within the box [lo, hi] (world XY): a convex polygon, its
  // corners counter-clockwise; empty when the two do not meet.
  std::vector<Eigen::Vector2d> Outline(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;

 private:
  // n . xy <= offset, n the unit direction to the other centre.
  struct HalfPlane {
    Eigen::Vector2d normal;
    double offset;
  };
  std::vector<HalfPlane> half_planes_;
};

}  // namespace sapmvs

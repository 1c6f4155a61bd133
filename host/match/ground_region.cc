#include "sapmvs/match/ground_region.h"

#include <cmath>

#include "sapmvs/util/error.h"

namespace sapmvs {

GroundRegion::GroundRegion(const std::vector<Eigen::Vector2d>& centers, int own, double margin) {
  if (own < 0 || own >= static_cast<int>(centers.size())) {
    throw Error("ground region: expected a group index in 0.." +
                std::to_string(static_cast<long>(centers.size()) - 1) + " (" + std::to_string(own) +
                ")");
  }
  if (!(std::isfinite(margin) && margin >= 0)) throw Error("ground region: expected a margin >= 0");
  const Eigen::Vector2d& c = centers[own];
  for (size_t j = 0; j < centers.size(); ++j) {
    const Eigen::Vector2d d = centers[j] - c;
    const double length = d.norm();
    if (static_cast<int>(j) == own || !(length > 0)) continue;
    HalfPlane h;
    h.normal = d / length;
    // The bisector, moved `margin` towards the other centre.
    h.offset = h.normal.dot((c + centers[j]) / 2) + margin;
    half_planes_.push_back(h);
  }
}

}  // namespace sapmvs

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

std::vector<Eigen::Vector2d> GroundRegion::Outline(const Eigen::Vector2d& lo,
                                                   const Eigen::Vector2d& hi) const {
  std::vector<Eigen::Vector2d> polygon = {
      {lo.x(), lo.y()}, {hi.x(), lo.y()}, {hi.x(), hi.y()}, {lo.x(), hi.y()}};
  // Sutherland-Hodgman: a convex polygon clipped by one half-plane at a time.
  for (const HalfPlane& h : half_planes_) {
    std::vector<Eigen::Vector2d> kept;
    for (size_t i = 0; i < polygon.size(); ++i) {
      const Eigen::Vector2d& a = polygon[i];
      const Eigen::Vector2d& b = polygon[(i + 1) % polygon.size()];
      const double da = h.normal.dot(a) - h.offset, db = h.normal.dot(b) - h.offset;
      if (da <= 0) kept.push_back(a);
      if ((da < 0 && db > 0) || (da > 0 && db < 0)) kept.push_back(a + (b - a) * (da / (da - db)));
    }
    polygon = std::move(kept);
    if (polygon.size() < 3) return {};
  }
  return polygon;
}

}  // namespace sapmvs

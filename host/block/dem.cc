#include "sapmvs/block/dem.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sapmvs/util/number_text.h"

namespace sapmvs {

double Dem::Height(double x, double y) const {
  // Cell centres sit at half-integer raster coordinates.
  const double col = (x - geo_[0]) / geo_[1] - 0.5;
  const double row = (y - geo_[3]) / geo_[5] - 0.5;
  if (!(col >= 0 && row >= 0 && col <= width_ - 1 && row <= height_ - 1)) return kNaN;
  const int c0 = std::min(static_cast<int>(col), std::max(width_ - 2, 0));
  const int r0 = std::min(static_cast<int>(row), std::max(height_ - 2, 0));
  const int c1 = std::min(c0 + 1, width_ - 1), r1 = std::min(r0 + 1, height_ - 1);
  const double fc = col - c0, fr = row - r0;
  auto at = [&](int r, int c) {
    return static_cast<double>(z_[static_cast<size_t>(r) * width_ + c]);
  };
  return (1 - fr) * ((1 - fc) * at(r0, c0) + fc * at(r0, c1)) +
         fr * ((1 - fc) * at(r1, c0) + fc * at(r1, c1));
}

Eigen::Vector3d Dem::Intersect(const Eigen::Vector3d& center, const Eigen::Vector3d& dir) const {
  const Eigen::Vector3d d = dir.normalized();
  if (!(d.z() < 0)) return Eigen::Vector3d::Constant(kNaN);
  // Start where the ray reaches the highest plausible surface, step half a
  // cell (in 3D) and refine the crossing by bisection.
  const double zmin = zmin_, zmax = zmax_;
  if (!std::isfinite(zmax)) return Eigen::Vector3d::Constant(kNaN);
  double t = std::max(0.0, (center.z() - zmax) / -d.z());
  const double step = 0.5 * cell_size();
  const double t_end = (center.z() - zmin) / -d.z() + step;
  double prev_t = -1;
  for (; t < t_end; t += step) {
    const Eigen::Vector3d p = center + t * d;
    const double h = Height(p.x(), p.y());
    if (std::isnan(h)) {
      if (prev_t >= 0) return Eigen::Vector3d::Constant(kNaN);
      continue;
    }
    if (p.z() <= h) {
      double lo = prev_t >= 0 ? prev_t : t - step, hi = t;
      for (int k = 0; k < 40; ++k) {
        const double mid = 0.5 * (lo + hi);
        const Eigen::Vector3d q = center + mid * d;
        const double hq = Height(q.x(), q.y());
        if (!std::isnan(hq) && q.z() <= hq)
          hi = mid;
        else
          lo = mid;
      }
      return center + hi * d;
    }
    prev_t = t;
  }
  return Eigen::Vector3d::Constant(kNaN);
}

double Dem::MedianHeight() const {
  std::vector<float> v;
  v.reserve(z_.size());
  for (float z : z_) {
    if (std::isfinite(z)) v.push_back(z);
  }
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

}  // namespace sapmvs

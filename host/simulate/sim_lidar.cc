#include "simulate/sim_lidar.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace sapmvs::sim {

double LidarDensityForGsd(double gsd) { return std::min(4.0, 1.0 / (9.0 * gsd * gsd)); }

std::vector<PointRecord> SimulateLidar(const Scene& scene, const LidarSpec& spec,
                                       const Eigen::Vector3d& offset, uint64_t seed) {
  std::mt19937_64 rng(seed * 104729 + 3);
  std::normal_distribution<double> nz(0, spec.noise_z), nxy(0, spec.noise_xy);
  const double spacing = 1 / std::sqrt(spec.density);
  const double half_swath = spec.flying_height * std::tan(spec.swath_half_angle * M_PI / 180);
  const double strip_step = 2 * half_swath * (1 - spec.side_overlap);
  std::vector<PointRecord> out;
  for (double ys = spec.min.y() + half_swath * 0.8; ys - half_swath < spec.max.y();
       ys += strip_step) {
    int line = 0;
    for (double x = spec.min.x(); x <= spec.max.x(); x += spacing, ++line) {
      // The mirror sweeps left and right on alternate lines: a zig-zag.
      const double phase = (line % 2 == 0) ? 0.0 : 0.5;
      for (double a = -half_swath + phase * spacing; a <= half_swath; a += spacing) {
        const double y = ys + (line % 2 == 0 ? a : -a);
        if (y < spec.min.y() || y > spec.max.y()) continue;
        const Eigen::Vector3d o(x, ys, spec.flying_height);
        const Eigen::Vector3d target(x + 0.2 * spacing * (a / half_swath), y, 0);
        const Hit hit = scene.Intersect(o, (target - o).normalized());
        if (!hit.valid) continue;
        PointRecord p;
        p.x = hit.point.x() + nxy(rng) + offset.x();
        p.y = hit.point.y() + nxy(rng) + offset.y();
        p.z = hit.point.z() + nz(rng) + offset.z();
        p.classification = LasClass(hit.cls);
        if (hit.wall) p.classification = 6;
        const double albedo = scene.Albedo(hit).mean();
        p.intensity = static_cast<uint16_t>(std::clamp(albedo, 0.0, 1.0) * 65535);
        out.push_back(p);
      }
    }
  }
  return out;
}

}  // namespace sapmvs::sim

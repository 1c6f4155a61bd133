#pragma once
// Simulated airborne laser scanning of a scene: parallel strips flown along X,
// a zig-zag scan across track, first returns (roofs, crowns, walls hit
// obliquely), centimetre noise. Density: 4 points/m^2 where the images' GSD is
// as fine as the paper's blocks, lowered for coarser simulated GSDs so that
// points stay about 3 GSD apart (the ratio of the paper's LiDAR to its images).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sapmvs/io/las_io.h"
#include "sapmvs/simulate/sim_scene.h"

namespace sapmvs::sim {

struct LidarSpec {
  double density = 4;            // points per m^2 (single strip)
  double flying_height = 500;    // m above the mean ground
  double swath_half_angle = 20;  // deg
  double side_overlap = 0.3;     // share of the swath
  double noise_z = 0.02;         // m (1 sigma)
  double noise_xy = 0.05;        // m (1 sigma)
  Eigen::Vector2d min, max;      // local area to cover
};

// Density for images of `gsd` metres: min(4, 1 / (3 gsd)^2).
double LidarDensityForGsd(double gsd);

// Points in world coordinates (local + offset), classified 2 (ground), 5
// (vegetation), 6 (building) or 9 (water), with intensity from the albedo.
std::vector<PointRecord> SimulateLidar(const Scene& scene, const LidarSpec& spec,
                                       const Eigen::Vector3d& offset, uint64_t seed);

}  // namespace sapmvs::sim

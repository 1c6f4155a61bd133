#pragma once
// The flight the simulator renders (FlightPlan, PlannedImage), apart from
// the simulator (simulate.h) so that its presets (host/simulate/sim_presets.h) can
// lay one out without it.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace sapmvs {

// One planned exposure: world coordinates and omega-phi-kappa in degrees.
struct PlannedImage {
  std::string name;
  int strip = 0;
  Eigen::Vector3d center;
  double omega = 0, phi = 0, kappa = 0;
  double gain = 1;  // exposure factor
};

namespace sim {

// The flight of a block: where each image is taken, and the geometry the
// overlaps give it. Image x (the sensor's long side for the presets' cameras)
// lies along track, as rotation.h's convention has it.
struct FlightPlan {
  std::vector<PlannedImage> images;  // local coordinates (before the world offset)
  int strips = 0;
  double gsd = 0;                                    // nominal, at the mean ground
  double flying_height = 0;                          // m above the mean ground
  double forward_overlap = 0, side_overlap = 0;      // shares of the footprint
  double footprint_along = 0, footprint_across = 0;  // m on the mean ground
  double base = 0;           // m between neighbouring exposures of a strip, before noise
  double strip_spacing = 0;  // m between neighbouring strips
  double scene_width = 0, scene_height = 0;  // m, covering every footprint with a margin

  // Degrees between the rays of two neighbours of a strip to the ground point
  // midway below them: what narrow baselines make small.
  double NeighbourAngleDeg() const;
};

}  // namespace sim

}  // namespace sapmvs

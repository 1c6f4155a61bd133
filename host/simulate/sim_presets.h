#pragma once
// Presets of `sapmvs simulate`: a camera, a flight plan and a scene each.

#include <string>
#include <vector>

#include "sapmvs/block/rotation.h"
#include "sapmvs/simulate/flight_plan.h"
#include "sapmvs/simulate/sim_scene.h"

namespace sapmvs::sim {

struct CameraSpec {
  double focal_mm = 8.8;
  double pixel_um = 2.4;
  int width = 640, height = 480;  // px
};

struct FlightSpec {
  std::vector<int> images_per_strip = {2, 2};
  double flying_height = 120;    // m above the mean ground
  double forward_overlap = 0.7;  // share of the along-track (image x) footprint
  double side_overlap = 0.35;    // share of the across-track (image y) footprint
  double attitude_noise = 1.5;   // deg, omega and phi; kappa gets 4/3 of it
  double exposure = 0.0;         // largest relative gain change between images
};

struct Preset {
  std::string name;
  std::string description;
  CameraSpec camera;
  FlightSpec flight;
  SceneSpec scene;            // width/height are set from the flight plan
  double cell_per_gsd = 0.5;  // scene cell size in nominal GSDs
  AngleOrder order = AngleOrder::kOmegaPhiKappa;
  AngleUnit unit = AngleUnit::kDegree;
};

// Throws sapmvs::Error naming the preset and the valid names.
Preset FindPreset(const std::string& name);
const std::vector<Preset>& AllPresets();

// Scales the camera's resolution by `scale` (the sensor stays the same).
CameraSpec ScaledCamera(const CameraSpec& camera, double scale);

// Lays out strips in alternating directions (kappa 0 flying +X, 180 flying
// -X), with attitude and position noise, and an optional cross strip (kappa
// 90, flying +Y); sizes the scene to cover every footprint with a margin.
FlightPlan PlanFlight(const Preset& preset, const CameraSpec& camera, bool cross_strip,
                      double exposure, uint64_t seed);

}  // namespace sapmvs::sim

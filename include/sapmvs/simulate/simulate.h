#pragma once
// `sapmvs simulate`: synthetic UAV/aerial blocks whose true surface is known
// exactly. A scene (sim_scene.h) is flown in strips with a frame camera and
// rendered by ray casting; the output folder holds a native block.yaml, the
// images, the truth DSM (GeoTIFF) and simulated airborne LiDAR (LAS).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sapmvs/block/rotation.h"
#include "sapmvs/simulate/flight_plan.h"
#include "sapmvs/simulate/sim_scene.h"

namespace sapmvs {

struct SimulateOptions {
  std::string preset = "tiny";  // tiny | small | campus | mountain | city | large
  std::filesystem::path out;    // output folder, created when missing
  uint64_t seed = 1;            // same seed, same bytes
  double scale = 1.0;  // image resolution factor: 0.5 halves width and height, doubles the GSD
  std::string angles;  // angle order written to block.yaml; empty = the preset's
  std::string units;   // angle unit written to block.yaml; empty = the preset's
  bool cross_strip = false;  // add one strip flown across the others
  // Forward and side overlap, percent of the footprint at the mean ground
  // (e.g. {88, 30}); empty = the preset's. The base is (1 - forward) x the
  // along-track footprint, the strip spacing (1 - side) x the across-track one.
  std::vector<double> overlap;
  // The flight's strips and images per strip, 0 = the preset's (its strip
  // count; its longest strip). Either one replaces the preset's uneven strips
  // by equal ones: the same flight, cut shorter or narrower, for scaling runs.
  int strips = 0;
  int strip_images = 0;
  double exposure = -1;   // largest relative exposure change between images; < 0 = the preset's
  int supersampling = 2;  // rays per pixel side (2 = 2x2 per pixel); 1 aliases edges and
                          // texture, a quarter of the time for timing runs at 12 MP
  double noise = 1.5;     // sensor noise, standard deviation in 8-bit grey levels
  bool xyz = false;       // also write truth/lidar.xyz
  // Write truth/ortho.tif, the true orthophoto (about a sixth of a small
  // block's render time).
  bool ortho = true;
  bool quiet = false;  // no progress bar

  // Empty when the options are usable, else one line naming the bad value.
  std::string Problem() const;
  bool Check() const { return Problem().empty(); }
};

std::vector<std::string> SimulatePresetNames();

// The flight Simulate flies for `options`, planned without the scene or any
// rendering (cheap, also for the big presets). Throws on bad options.
sim::FlightPlan PlanSimulatedFlight(const SimulateOptions& options);

struct SimulateSummary {
  int images = 0;
  int strips = 0;
  int width = 0, height = 0;
  double gsd = 0;  // nominal, at the mean ground height
  double flying_height = 0;
  double forward_overlap = 0, side_overlap = 0;  // shares of the footprint
  double base = 0;                               // m between neighbours of a strip
  double neighbour_angle = 0;                    // deg, see FlightPlan
  long lidar_points = 0;
  AngleOrder order = AngleOrder::kOmegaPhiKappa;
  AngleUnit unit = AngleUnit::kDegree;
};

// The scene, flight plan and world offset that Simulate renders for
// `options`: tests rebuild them to compare the outputs with the truth.
struct SimulatedWorld {
  sim::Scene scene;
  sim::FlightPlan flight;     // the images, in local coordinates
  Eigen::Vector3d offset;     // world = local + offset
  int width = 0, height = 0;  // image size, px
  double focal_mm = 0, pixel_um = 0;
};
SimulatedWorld BuildWorld(const SimulateOptions& options);

// Runs the whole simulation into options.out. Throws sapmvs::Error on bad
// options or when an output cannot be written; every file is written under a
// temporary name and renamed, so no partial file is left behind.
SimulateSummary Simulate(const SimulateOptions& options);

namespace sim {

// The 8-bit value a linear colour channel is recorded as (gain, then a 2.2
// display gamma), shared by the renderer and its tests.
double EncodeChannel(double linear, double gain);

// The world offset added to local scene coordinates (UTM-like, so float32
// mistakes show).
Eigen::Vector3d WorldOffset(double scene_width, double scene_height);

}  // namespace sim
}  // namespace sapmvs

#pragma once
// The simulator's synthetic scene: a first-surface height field on a regular
// grid of square cells whose tops are flat (so walls are exactly vertical and
// the truth DSM is exactly the cells' heights), with a class and a feature id
// per cell, a non-periodic multi-scale albedo and Lambertian shading.
// Coordinates are local metres (x east, y north, z up) from the grid's
// south-west corner; the simulator adds the UTM-like offset on output.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace sapmvs::sim {

enum class SurfaceClass : uint8_t { kGrass, kRoad, kSquare, kRoof, kTree, kWater, kBareSoil };

// The ASPRS LAS code of a class: 2 ground, 5 high vegetation, 6 building,
// 9 water (the LiDAR's classification and truth/classes.tif).
uint8_t LasClass(SurfaceClass k);

// What a scene holds and how dense it is. All lengths in metres.
struct SceneSpec {
  double width = 400;                           // x extent
  double height = 300;                          // y extent
  double cell = 0.25;                           // grid cell size
  double relief = 4;                            // terrain amplitude (peak to mean)
  double relief_wavelength = 250;               // dominant terrain wavelength
  double road_spacing = 90;                     // mean distance between roads (0 = none)
  int squares = 2;                              // paved flat squares
  double building_density = 0.25;               // share of free land covered by buildings
  double building_min = 12, building_max = 45;  // footprint side range
  double storey_min = 2, storey_max = 6;        // storeys (3 m each)
  double pitched_share = 0.4;                   // share of pitched roofs
  int high_rises = 1;                           // 40 to 80 m towers
  double tree_density = 0.08;                   // share of free land under crowns
  double water_share = 0.04;                    // share of the area under water
  bool Check() const;
};

struct Hit {
  bool valid = false;
  Eigen::Vector3d point;
  Eigen::Vector3d normal;
  SurfaceClass cls = SurfaceClass::kGrass;
  uint16_t feature = 0;  // building / tree index, 0 = none
  bool wall = false;
};

class Scene {
 public:
  // Builds a scene from `spec`, deterministic for a given `seed`.
  static Scene Generate(const SceneSpec& spec, uint64_t seed);

  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double cell() const { return cell_; }
  double width() const { return nx_ * cell_; }
  double height() const { return ny_ * cell_; }
  double min_height() const { return zmin_; }
  double max_height() const { return zmax_; }

  // Height of the cell containing (x, y) (the truth DSM); NaN outside.
  double HeightAt(double x, double y) const;
  float CellHeight(int ix, int iy) const { return z_[Index(ix, iy)]; }
  SurfaceClass CellClass(int ix, int iy) const {
    return static_cast<SurfaceClass>(cls_[Index(ix, iy)]);
  }

  // First intersection of the ray o + t d (t > 0) with the cell columns.
  Hit Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const;
  // Surface point of the top of the cell containing (x, y), as a Hit.
  Hit TopAt(double x, double y) const;

  // Linear RGB albedo in [0, 1] and shaded colour (albedo times the
  // Lambertian term for the fixed sun, plus sky light).
  Eigen::Vector3d Albedo(const Hit& hit) const;
  Eigen::Vector3d Shade(const Hit& hit) const;
  const Eigen::Vector3d& sun() const { return sun_; }

 private:
  size_t Index(int ix, int iy) const { return static_cast<size_t>(iy) * nx_ + ix; }
  Eigen::Vector3d TopNormal(int ix, int iy) const;
  void BuildBlockMax();

  int nx_ = 0, ny_ = 0;
  double cell_ = 1;
  uint64_t seed_ = 0;
  std::vector<float> z_;
  std::vector<uint8_t> cls_;
  std::vector<uint16_t> feature_;
  std::vector<Eigen::Vector3f> feature_colour_;  // per feature id
  // Max height per kBlock x kBlock cells: rays skip whole blocks above it.
  static constexpr int kBlock = 16;
  int bx_ = 0, by_ = 0;
  std::vector<float> block_max_;
  double zmin_ = 0, zmax_ = 0;
  Eigen::Vector3d sun_;
};

// Deterministic hash noise (no lattice period): value noise in [0, 1] at
// `frequency` cycles per metre, summed over `octaves` halving amplitudes.
double FractalNoise(double x, double y, double frequency, int octaves, uint64_t seed);

}  // namespace sapmvs::sim

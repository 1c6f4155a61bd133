#pragma once
// A synthetic scene for kernel tests: a textured ground plane z = 0 (local frame)
// seen by pinhole cameras looking down from about 40 m with random tilts; the images
// are rendered by casting each pixel's ray onto the plane, so the true plane is
// photo-consistent.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "device/ncc_scorer.h"
#include "match/group_data.h"
#include "sapmvs/block/camera.h"

namespace sapmvs::test {

struct PlaneScene {
  std::vector<std::vector<float>> pixels;
  std::vector<Camera> cameras;  // Local frame.
  NccGroup group;
  // Texture: a sum of 16 plane waves (wavelengths 0.8 to 3 m, i.e. about 3 to
  // 11 pixels), non-periodic enough that a shifted patch does not match.
  std::vector<Eigen::Vector4d> waves;  // (kx, ky, phase, amplitude).

  double Texture(double x, double y) const {
    double value = 128.0;
    for (const Eigen::Vector4d& w : waves) value += w[3] * std::sin(w[0] * x + w[1] * y + w[2]);
    return value;
  }
};

// `num_images` cameras of `width` x `height` px over the plane, deterministic
// for `seed`. With `strip_base` > 0 (m), the centres lie on a strip along x
// at 40 m, that far apart, image 0 in the middle (0, -b, +b, -2b, ...).
PlaneScene MakePlaneScene(int num_images, int width, int height, uint32_t seed,
                          double strip_base = 0);

// The scene as a match group: every image matched with all the others. The
// group's kernel views point into the scene's pixels, which must outlive it.
MatchGroupData MatchGroupOf(const PlaneScene& scene);

// Ground point (z = 0) seen at pixel `uv` of `camera`.
Eigen::Vector3d GroundAt(const Camera& camera, const Eigen::Vector2d& uv);

// A plane to start a refinement from.
struct PlaneStart {
  Eigen::Vector3d center, normal;
};

// `count` starts on the ground under random pixels of image 0 within
// `spread` (x, y) pixels of its centre, `depth_offset` footprints off along
// the ray (alternately in front and behind) and `tilt_deg` off in normal,
// about a horizontal axis that turns with the start's index.
std::vector<PlaneStart> PerturbedStarts(const PlaneScene& scene, int count, double depth_offset,
                                        double tilt_deg, const Eigen::Vector2d& spread,
                                        uint32_t seed);

}  // namespace sapmvs::test

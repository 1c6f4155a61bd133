#include "plane_scene.h"

#include <Eigen/Geometry>
#include <random>

namespace sapmvs::test {

PlaneScene MakePlaneScene(int num_images, int width, int height, uint32_t seed, double strip_base) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  PlaneScene scene;
  constexpr double kPi = 3.14159265358979323846;
  for (int k = 0; k < 16; ++k) {
    const double wavelength = 0.8 + 2.2 * (0.5 + 0.5 * unit(rng));
    const double angle = kPi * unit(rng);
    const double kmag = 2.0 * kPi / wavelength;
    // Named draws, last argument first: the order in which a call's
    // arguments are evaluated is the compiler's, and these scenes must be
    // the same from gcc and clang (gcc evaluated them last to first).
    const double amplitude = 8.0 + 4.0 * unit(rng);
    const double phase = kPi * unit(rng);
    scene.waves.emplace_back(kmag * std::cos(angle), kmag * std::sin(angle), phase, amplitude);
  }
  // Georeferenced-looking world coordinates, translated to a local origin as
  // the block does; the texture and patches live in the local frame.
  const Eigen::Vector3d origin(500000.0, 6000000.0, 100.0);
  const Intrinsics intrinsics = Intrinsics::FromPixels(150.0, 152.0, 0.5 * (width - 1) + 2.0,
                                                       0.5 * (height - 1) - 1.5, width, height);
  for (int i = 0; i < num_images; ++i) {
    const double z = 40.0 + 3.0 * unit(rng);  // last to first, as the waves
    const double y = 6.0 * unit(rng);
    Eigen::Vector3d center(6.0 * unit(rng), y, z);
    if (strip_base > 0) {
      // 0, -b, +b, -2b, +2b, ... along x at 40 m: image 0 in the middle.
      const int step = (i + 1) / 2;
      center = Eigen::Vector3d((i % 2 ? -1.0 : 1.0) * step * strip_base, 0.0, 40.0);
    }
    // Nadir (camera x = world x, y = -world y, z down), then a yaw and a tilt
    // of up to about 12 degrees.
    Eigen::Matrix3d r_cw;
    r_cw.col(0) = Eigen::Vector3d(1, 0, 0);
    r_cw.col(1) = Eigen::Vector3d(0, -1, 0);
    r_cw.col(2) = Eigen::Vector3d(0, 0, -1);
    const double yaw = kPi * unit(rng);  // last to first, as the waves
    const double pitch = 0.2 * unit(rng);
    const double roll = 0.2 * unit(rng);
    const Eigen::Matrix3d tilt = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()))
                                     .toRotationMatrix();
    const Camera world(intrinsics, (tilt * r_cw).transpose(), center + origin);
    scene.cameras.push_back(world.Translated(origin));
  }
  for (const Camera& camera : scene.cameras) {
    std::vector<float> image(static_cast<size_t>(width) * height);
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const Eigen::Vector3d d = camera.Ray(Eigen::Vector2d(u, v));
        const Eigen::Vector3d x = camera.center() - (camera.center().z() / d.z()) * d;
        image[static_cast<size_t>(v) * width + u] = static_cast<float>(scene.Texture(x.x(), x.y()));
      }
    }
    scene.pixels.push_back(std::move(image));
  }
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    scene.group.images.push_back({scene.pixels[i].data(), {width, height, width}});
    scene.group.cameras.push_back(MakeNccCamera(scene.cameras[i]));
  }
  return scene;
}

Eigen::Vector3d GroundAt(const Camera& camera, const Eigen::Vector2d& uv) {
  const Eigen::Vector3d d = camera.Ray(uv);
  return camera.center() - (camera.center().z() / d.z()) * d;
}

MatchGroupData MatchGroupOf(const PlaneScene& scene) {
  MatchGroupData group;
  for (size_t i = 0; i < scene.cameras.size(); ++i) {
    MatchImage image;
    image.camera = scene.cameras[i];
    for (size_t j = 0; j < scene.cameras.size(); ++j) {
      if (j != i) image.views.push_back(static_cast<int>(j));
    }
    group.images.push_back(image);
  }
  group.ncc = scene.group;
  return group;
}

std::vector<PlaneStart> PerturbedStarts(const PlaneScene& scene, int count, double depth_offset,
                                        double tilt_deg, const Eigen::Vector2d& spread,
                                        uint32_t seed) {
  constexpr double kPi = 3.14159265358979323846;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Camera& ref = scene.cameras[0];
  std::vector<PlaneStart> starts;
  for (int i = 0; i < count; ++i) {
    const double v = 0.5 * (ref.height() - 1) + spread.y() * unit(rng);  // as in MakePlaneScene
    const Eigen::Vector2d uv(0.5 * (ref.width() - 1) + spread.x() * unit(rng), v);
    const Eigen::Vector3d truth = GroundAt(ref, uv);
    const Eigen::Vector3d ray = (truth - ref.center()).normalized();
    const double footprint = ref.Depth(truth) / ref.intrinsics().MeanFocal();
    const double sign = (i % 2 == 0) ? 1.0 : -1.0;
    const double azimuth = 2.0 * kPi * i / count;
    const Eigen::Vector3d axis(std::cos(azimuth), std::sin(azimuth), 0.0);
    starts.push_back(
        PlaneStart{truth + sign * depth_offset * footprint * ray,
                   Eigen::AngleAxisd(tilt_deg * kPi / 180.0, axis) * Eigen::Vector3d::UnitZ()});
  }
  return starts;
}

}  // namespace sapmvs::test

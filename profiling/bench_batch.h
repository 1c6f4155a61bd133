#pragma once
// The synthetic batch the NCC and refinement benchmarks share: 4 random
// textured 640x480 images (smoothed noise: texture without rendering a
// scene; the rates do not depend on the NCC values), one nadir camera each
// 40 m above a ground plane, 4 m apart, and patches on the plane under
// random reference pixels, each paired with the three other images.
#include <Eigen/Core>

#include <random>
#include <vector>

#include "device/ncc_scorer.h"

namespace sapmvs {
namespace {

constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr int kNumImages = 4;

struct Batch {
  std::vector<std::vector<float>> pixels;
  NccGroup group;
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
};

// Smoothed noise images (texture without rendering a scene: the rate does not
// depend on the NCC values) and cameras 40 m above a plane, 4 m apart.
Batch MakeBatch(int num_pairs) {
  Batch batch;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(0.0f, 255.0f);
  const Intrinsics intrinsics = Intrinsics::FromPixels(600, 600, 319.5, 239.5, kWidth, kHeight);
  Eigen::Matrix3d r_wc;
  r_wc << 1, 0, 0, 0, -1, 0, 0, 0, -1;  // Looking straight down.
  std::vector<Camera> cameras;
  for (int i = 0; i < kNumImages; ++i) {
    std::vector<float> image(static_cast<size_t>(kWidth) * kHeight);
    for (float& p : image) p = value(rng);
    for (size_t k = 1; k < image.size(); ++k) image[k] = 0.5f * (image[k] + image[k - 1]);
    batch.pixels.push_back(std::move(image));
    cameras.emplace_back(intrinsics, r_wc, Eigen::Vector3d(4.0 * (i % 2), 4.0 * (i / 2), 40.0));
    batch.group.images.push_back({batch.pixels.back().data(), {kWidth, kHeight, kWidth}});
    batch.group.cameras.push_back(MakeNccCamera(cameras.back()));
  }
  std::uniform_real_distribution<double> u(0.0, kWidth - 1.0);
  std::uniform_real_distribution<double> v(0.0, kHeight - 1.0);
  const int views_per_patch = kNumImages - 1;
  for (int p = 0; p * views_per_patch < num_pairs; ++p) {
    const int reference = p % kNumImages;
    const Camera& camera = cameras[reference];
    const Eigen::Vector3d d = camera.Ray(Eigen::Vector2d(u(rng), v(rng)));
    const Eigen::Vector3d ground = camera.center() - (camera.center().z() / d.z()) * d;
    batch.patches.push_back(MakeNccPatch(ground, Eigen::Vector3d::UnitZ(), reference));
    for (int view = 0; view < kNumImages && static_cast<int>(batch.pairs.size()) < num_pairs;
         ++view) {
      if (view != reference) batch.pairs.push_back({p, view});
    }
  }
  return batch;
}

}  // namespace
}  // namespace sapmvs

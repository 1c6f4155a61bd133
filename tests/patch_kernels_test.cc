// PatchKernels, the wall between the matcher and the device: the backend a
// device spec selects, the CPU reference behind the interface (it must be the
// double-precision references, rounded to float), and the two backends
// against each other on a plane scene, at odd sizes and at the borders.

#include "match/patch_kernels.h"
#include "device/make_patch_kernels.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "cl_test_fixture.h"
#include "device/cl_patch_kernels.h"
#include "match/ncc_score_reference.h"
#include "match/patch_refine_reference.h"
#include "match/reference_patch_kernels.h"
#include "plane_scene.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::ClTest;
using test::MakePlaneScene;
using test::NearAbsRel;
using test::PlaneScene;

// Scores, device vs reference: as ncc_scorer_test (float32 sums of up to 441
// samples; a wrong sample or axis moves the NCC by 1e-2 or more).
constexpr double kNccAbsTol = 1e-4;
constexpr double kNccRelTol = 1e-4;
// Pixels from an image's valid region within which float32 and double
// positions may fall on different sides of the border (ncc_scorer_test).
constexpr double kNccBorderAmbiguity = 1e-3;
// Refinement, device vs reference: as patch_refiner_test. Float32 can flip a
// late near-tie of the search, so the final score is compared with a
// tolerance; where every decision had a margin above kSafeMargin the two
// take the same path and the parameters agree to float precision.
constexpr double kScoreTol = 2e-3;
constexpr double kSafeMargin = 1e-4;
constexpr double kDepthTol = 1e-3;  // Footprints.
constexpr double kAngleTol = 1e-4;  // Radians.

// Patches on or near the ground under random pixels of random reference
// images, half of them within 6 px of a border (either side), normals tilted
// up to about 25 degrees; each paired with every image.
void RandomBackendBatch(const PlaneScene& scene, int num_patches, uint32_t seed,
                        std::vector<NccPatch>* patches, std::vector<NccPair>* pairs) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int num_images = static_cast<int>(scene.cameras.size());
  for (int p = 0; p < num_patches; ++p) {
    const int reference = static_cast<int>(rng() % num_images);
    const Camera& camera = scene.cameras[reference];
    const double w = camera.width(), h = camera.height();
    Eigen::Vector2d uv(0.5 * (w - 1) * (1 + unit(rng)), 0.5 * (h - 1) * (1 + unit(rng)));
    if (p % 2 == 0) {
      const double band = 6.0 * unit(rng);
      const int side = static_cast<int>(rng() % 4);
      if (side < 2) uv.x() = side == 0 ? band : w - 1 + band;
      if (side >= 2) uv.y() = side == 2 ? band : h - 1 + band;
    }
    const Eigen::Vector3d normal =
        Eigen::Vector3d(0.45 * unit(rng), 0.45 * unit(rng), 1.0).normalized();
    const Eigen::Vector3d center = test::GroundAt(camera, uv) + 0.3 * unit(rng) * normal;
    patches->push_back(MakeNccPatch(center, normal, reference));
    for (int v = 0; v < num_images; ++v) pairs->push_back({p, v});
  }
}

void PerturbedPatches(const PlaneScene& scene, int count, uint32_t seed,
                      std::vector<NccPatch>* patches, std::vector<std::vector<int>>* views) {
  for (const test::PlaneStart& s :
       test::PerturbedStarts(scene, count, 2.0, 10.0, {20.0, 15.0}, seed)) {
    patches->push_back(MakeNccPatch(s.center, s.normal, 0));
    views->push_back({1, 2, 3});
  }
}

std::unique_ptr<PatchKernels> Reference() {
  PatchKernelsOptions options;
  options.device = kReferenceDevice;
  return MakePatchKernels(options);
}

TEST(PatchKernelsTest, DeviceSpecSelectsTheReference) {
  const test::ScopedEnv no_env("SAPMVS_DEVICE", std::nullopt);
  for (const char* spec : {"reference", " Reference ", "REFERENCE"}) {
    EXPECT_TRUE(SelectsReference({spec, false})) << spec;
  }
  for (const char* spec : {"", "0", "pocl", "references", "ref"}) {
    EXPECT_FALSE(SelectsReference({spec, false})) << spec;
  }
  const test::ScopedEnv env("SAPMVS_DEVICE", "reference");
  EXPECT_TRUE(SelectsReference({"", false}));
  EXPECT_FALSE(SelectsReference({"pocl", false})) << "--device wins over SAPMVS_DEVICE";
  const std::unique_ptr<PatchKernels> kernels = MakePatchKernels({"", false});
  EXPECT_EQ(kernels->device().name, "reference");
  EXPECT_EQ(kernels->device().type, "CPU");
}

// The CPU backend is the double references, rounded to float: nothing lost
// or reordered on the way through the interface.
TEST(ReferencePatchKernelsTest, IsTheDoubleReferenceInFloat) {
  const PlaneScene scene = MakePlaneScene(4, 97, 83, 71);
  const std::unique_ptr<PatchKernels> kernels = Reference();
  kernels->SetGroup(scene.group);
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  RandomBackendBatch(scene, 60, 72, &patches, &pairs);
  NccScorerOptions so;
  so.patch_size = 9;
  so.sigma_color = 3.0;
  double seconds = -1;
  const std::vector<float> scores = kernels->Score(so, patches, pairs, &seconds);
  EXPECT_EQ(seconds, 0.0) << "no time without profiling";
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, 9, nullptr, 3.0);
  ASSERT_EQ(scores.size(), expected.size());
  int nan = 0;
  for (size_t i = 0; i < scores.size(); ++i) {
    nan += std::isnan(expected[i]) ? 1 : 0;
    if (std::isnan(expected[i])) {
      EXPECT_TRUE(std::isnan(scores[i])) << "pair " << i;
    } else {
      EXPECT_EQ(scores[i], static_cast<float>(expected[i])) << "pair " << i;
    }
  }
  EXPECT_GT(nan, 0) << "the batch should reach past the borders";
  EXPECT_LT(nan, static_cast<int>(pairs.size()));

  const PlaneScene wide = MakePlaneScene(4, 161, 123, 75);
  kernels->SetGroup(wide.group);
  std::vector<NccPatch> starts;
  std::vector<std::vector<int>> views;
  PerturbedPatches(wide, 6, 73, &starts, &views);
  PatchRefinerOptions ro;
  ro.patch_size = 7;
  ro.iterations = 10;
  const std::vector<RefinedPatch> refined = kernels->Refine(ro, starts, views, nullptr);
  const std::vector<RefinedPatchReference> want =
      PatchRefineReference(wide.group, starts, views, ro);
  ASSERT_EQ(refined.size(), want.size());
  for (size_t i = 0; i < refined.size(); ++i) {
    const RefinedPatch& r = refined[i];
    if (std::isnan(want[i].score)) {
      EXPECT_TRUE(std::isnan(r.score)) << "patch " << i;
      continue;
    }
    EXPECT_EQ(r.score, static_cast<float>(want[i].score)) << "patch " << i;
    EXPECT_EQ(r.moves, want[i].moves) << "patch " << i;
    EXPECT_EQ(r.evaluations, want[i].evaluations) << "patch " << i;
    EXPECT_EQ(r.patch.reference, starts[i].reference);
    EXPECT_LT((Xyz(r.patch.center) - want[i].center).norm(), 1e-3 * want[i].center.norm());
    EXPECT_NEAR(r.depth_offset, want[i].depth_offset, 1e-6);
    ASSERT_EQ(r.view_scores.size(), want[i].view_scores.size());
  }
}

TEST(ReferencePatchKernelsTest, RejectsBadCallsBeforeAnyWork) {
  const PlaneScene scene = MakePlaneScene(3, 61, 47, 74);
  const std::unique_ptr<PatchKernels> kernels = Reference();
  const std::vector<NccPatch> patches = {
      MakeNccPatch(test::GroundAt(scene.cameras[0], {30, 23}), Eigen::Vector3d::UnitZ(), 0)};
  EXPECT_THROW(kernels->Score({}, patches, {{0, 1}}, nullptr), Error) << "no group yet";
  kernels->SetGroup(scene.group);
  EXPECT_NO_THROW(kernels->Score({}, patches, {{0, 1}}, nullptr));
  NccScorerOptions even;
  even.patch_size = 8;
  EXPECT_THROW(kernels->Score(even, patches, {{0, 1}}, nullptr), Error);
  EXPECT_THROW(kernels->Score({}, patches, {{0, 3}}, nullptr), Error) << "view outside the group";
  EXPECT_THROW(kernels->Score({}, patches, {{1, 0}}, nullptr), Error) << "patch outside the batch";
  EXPECT_THROW(kernels->Refine({}, patches, {{0}}, nullptr), Error) << "its own reference";
  kernels->ClearGroup();
  EXPECT_THROW(kernels->Score({}, patches, {{0, 1}}, nullptr), Error) << "group cleared";
  NccGroup bad = scene.group;
  bad.cameras.pop_back();
  EXPECT_THROW(kernels->SetGroup(bad), Error);
}

struct BackendCase {
  int patch_size;
  int width;
  int height;
  uint32_t seed;
  double sigma_color;
  double sample_step = 1.0;
};

void PrintTo(const BackendCase& c, std::ostream* out) {
  *out << "patch " << c.patch_size << ", " << c.width << "x" << c.height << ", sigma "
       << c.sigma_color << ", step " << c.sample_step;
}

class PatchKernelsBackendsTest : public ClTest,
                                 public ::testing::WithParamInterface<BackendCase> {};

// The OpenCL backend and the CPU reference score alike, borders included.
TEST_P(PatchKernelsBackendsTest, ScoresAgree) {
  const BackendCase& c = GetParam();
  const PlaneScene scene = MakePlaneScene(4, c.width, c.height, c.seed);
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  RandomBackendBatch(scene, 150, c.seed + 1, &patches, &pairs);
  NccScorerOptions so;
  so.patch_size = c.patch_size;
  so.sigma_color = c.sigma_color;
  so.sample_step = c.sample_step;
  const std::unique_ptr<PatchKernels> device = MakeClPatchKernels(context());
  const std::unique_ptr<PatchKernels> reference = Reference();
  device->SetGroup(scene.group);
  reference->SetGroup(scene.group);
  const std::vector<float> got = device->Score(so, patches, pairs, nullptr);
  const std::vector<float> want = reference->Score(so, patches, pairs, nullptr);
  std::vector<double> margin;
  NccScoreReference(scene.group, patches, pairs, c.patch_size, &margin, c.sigma_color,
                    c.sample_step);
  ASSERT_EQ(got.size(), want.size());
  int valid = 0, nan = 0, ambiguous = 0;
  double worst = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    if (std::abs(margin[i]) < kNccBorderAmbiguity && std::isnan(got[i]) != std::isnan(want[i])) {
      ++ambiguous;
      continue;
    }
    EXPECT_TRUE(NearAbsRel(got[i], want[i], kNccAbsTol, kNccRelTol)) << "pair " << i;
    if (std::isnan(want[i])) {
      ++nan;
    } else {
      ++valid;
      worst = std::max(worst, static_cast<double>(std::abs(got[i] - want[i])));
    }
  }
  std::printf("[ BACKENDS ] patch %d: %d valid, %d NaN, %d ambiguous, worst |error| %.3g\n",
              c.patch_size, valid, nan, ambiguous, worst);
  EXPECT_GT(valid, static_cast<int>(pairs.size()) / 5);
  EXPECT_GT(nan, static_cast<int>(pairs.size()) / 20);
  EXPECT_LE(ambiguous, static_cast<int>(pairs.size()) / 200);
}

// ... and refine alike: the same path wherever no decision was a near-tie.
TEST_P(PatchKernelsBackendsTest, RefinementsAgree) {
  const BackendCase& c = GetParam();
  if (c.patch_size < 7) GTEST_SKIP() << "the matcher refines at 7 x 7 and larger";
  const PlaneScene scene = MakePlaneScene(4, 201, 161, c.seed);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 10, c.seed + 2, &patches, &views);
  const std::unique_ptr<PatchKernels> device = MakeClPatchKernels(context());
  device->SetGroup(scene.group);
  PatchRefinerOptions ro;
  ro.patch_size = c.patch_size;
  ro.sigma_color = c.sigma_color;
  ro.sample_step = c.sample_step;
  // The matcher's search, then a short one whose steps stay large, so that
  // most decisions are clear and the paths must be the same.
  for (const int iterations : {kDefaultRefineIterations, 4}) {
    ro.iterations = iterations;
    const std::vector<RefinedPatch> got = device->Refine(ro, patches, views, nullptr);
    const std::vector<RefinedPatchReference> want =
        PatchRefineReference(scene.group, patches, views, ro);
    ASSERT_EQ(got.size(), want.size());
    int same_path = 0, valid = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      // NaN: no start or move of the search was valid in every view.
      EXPECT_EQ(std::isnan(got[i].score), std::isnan(want[i].score)) << "patch " << i;
      if (std::isnan(want[i].score) || std::isnan(got[i].score)) continue;
      ++valid;
      EXPECT_NEAR(got[i].score, want[i].score, kScoreTol) << "patch " << i;
      if (want[i].decision_margin <= kSafeMargin) continue;
      ++same_path;
      EXPECT_EQ(got[i].moves, want[i].moves) << "patch " << i;
      EXPECT_EQ(got[i].evaluations, want[i].evaluations) << "patch " << i;
      EXPECT_NEAR(got[i].depth_offset, want[i].depth_offset, kDepthTol) << "patch " << i;
      EXPECT_NEAR(got[i].yaw, want[i].yaw, kAngleTol) << "patch " << i;
      EXPECT_NEAR(got[i].pitch, want[i].pitch, kAngleTol) << "patch " << i;
    }
    std::printf("[ BACKENDS ] refine %d, %d iterations: %d valid, %d of %zu on the same path\n",
                c.patch_size, iterations, valid, same_path, got.size());
    EXPECT_GE(valid, static_cast<int>(got.size()) / 2);
    if (iterations == 4) {
      EXPECT_GE(same_path, valid / 2);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(OddSizes, PatchKernelsBackendsTest,
                         ::testing::Values(BackendCase{3, 97, 83, 81, 0.0},
                                           BackendCase{7, 161, 123, 85, 3.0},
                                           BackendCase{11, 131, 97, 83, 0.0},
                                           BackendCase{21, 201, 161, 84, 3.0},
                                           // A 15 px window on 9 samples (SampledWindow).
                                           BackendCase{9, 163, 121, 86, 3.0, 1.75}));

}  // namespace
}  // namespace sapmvs

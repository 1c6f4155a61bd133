#include "device/ncc_scorer.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "plane_scene.h"
#include "sapmvs/block/rotation.h"
#include "sapmvs/util/kernel_limits.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::ClTest;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

using test::NearAbsRel;

// The NCC divides centred float32 sums of up to 121 bilinear samples whose
// positions come from float32 projections (about 1e-5 px off the double ones
// on these scenes). The worst error seen on PoCL is printed by each run and
// was 2.7e-6; the tolerance leaves over 30x room for FMA contraction and other
// devices' rounding while still catching a wrong sample or axis (which moves
// the NCC by 1e-2 or more).
constexpr double kAbsTol = 1e-4;
constexpr double kRelTol = 1e-4;
// Within this distance (pixels) of an image's valid region a sample's float32
// position may fall on the other side of the border than its double one, so
// the NaN decision may legitimately differ; the test counts such pairs.
constexpr double kBorderAmbiguity = 1e-3;

using test::MakePlaneScene;
using test::PlaneScene;

using test::GroundAt;

// Random patches: centres on or near the ground under random reference pixels
// (a band beyond every border included, so both NaN outcomes occur), normals
// tilted up to about 30 degrees; every patch paired with every image.
void RandomBatch(const PlaneScene& scene, int num_patches, uint32_t seed,
                 std::vector<NccPatch>* patches, std::vector<NccPair>* pairs) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int num_images = static_cast<int>(scene.cameras.size());
  for (int p = 0; p < num_patches; ++p) {
    const int reference = static_cast<int>(rng() % num_images);
    const Camera& camera = scene.cameras[reference];
    const double w = camera.width();
    const double h = camera.height();
    // Half the patches within 8 px of a border, where the NaN policy decides.
    Eigen::Vector2d uv(0.5 * (w - 1) * (1 + unit(rng)), 0.5 * (h - 1) * (1 + unit(rng)));
    if (p % 2 == 0) {
      const double band = 8.0 * unit(rng);
      switch (rng() % 4) {
        case 0:
          uv.x() = band;
          break;
        case 1:
          uv.x() = w - 1 + band;
          break;
        case 2:
          uv.y() = band;
          break;
        default:
          uv.y() = h - 1 + band;
          break;
      }
    }
    const Eigen::Vector3d normal =
        Eigen::Vector3d(0.5 * unit(rng), 0.5 * unit(rng), 1.0).normalized();
    const Eigen::Vector3d center = GroundAt(camera, uv) + 0.3 * unit(rng) * normal;
    patches->push_back(MakeNccPatch(center, normal, reference));
    for (int v = 0; v < num_images; ++v) pairs->push_back({p, v});
  }
}

struct Comparison {
  double worst_error = 0.0;
  int num_valid = 0;
  int num_nan = 0;
  int num_ambiguous = 0;
};

// Kernel vs reference, pair by pair; ambiguous border cases only counted.
Comparison CompareWithReference(const std::vector<float>& scores,
                                const std::vector<double>& expected,
                                const std::vector<double>& margin) {
  Comparison result;
  EXPECT_EQ(scores.size(), expected.size());
  for (size_t i = 0; i < std::min(scores.size(), expected.size()); ++i) {
    if (std::abs(margin[i]) < kBorderAmbiguity &&
        std::isnan(scores[i]) != std::isnan(expected[i])) {
      ++result.num_ambiguous;
      continue;
    }
    EXPECT_TRUE(NearAbsRel(scores[i], expected[i], kAbsTol, kRelTol)) << "pair " << i;
    if (std::isnan(expected[i])) {
      ++result.num_nan;
    } else {
      ++result.num_valid;
      result.worst_error = std::max(result.worst_error, std::abs(scores[i] - expected[i]));
    }
  }
  return result;
}

struct ScoreCase {
  int patch_size;
  int width;
  int height;
  uint32_t seed;
  double sigma_color = 0.0;
};

void PrintTo(const ScoreCase& c, std::ostream* out) {
  *out << "patch " << c.patch_size << ", " << c.width << "x" << c.height << ", seed " << c.seed
       << ", sigma_color " << c.sigma_color;
}

std::string ScoreCaseName(const ::testing::TestParamInfo<ScoreCase>& info) {
  return "patch" + std::to_string(info.param.patch_size) + "_" + std::to_string(info.param.width) +
         "x" + std::to_string(info.param.height) +
         (info.param.sigma_color > 0
              ? "_sigma" + std::to_string(static_cast<int>(info.param.sigma_color))
              : "");
}

class NccScorerCaseTest : public ClTest, public ::testing::WithParamInterface<ScoreCase> {};

TEST_P(NccScorerCaseTest, MatchesDoubleReference) {
  const ScoreCase& c = GetParam();
  const PlaneScene scene = MakePlaneScene(4, c.width, c.height, c.seed);
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  RandomBatch(scene, 400, c.seed + 1, &patches, &pairs);

  NccScorerOptions options;
  options.patch_size = c.patch_size;
  options.sigma_color = c.sigma_color;
  NccScorer scorer(context(), options);
  scorer.SetGroup(scene.group);
  const std::vector<float> scores = scorer.Score(patches, pairs);
  std::vector<double> margin;
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, c.patch_size, &margin, c.sigma_color);
  const Comparison result = CompareWithReference(scores, expected, margin);
  std::printf(
      "[ NCC      ] patch %d, sigma %g: %d valid, %d NaN, %d ambiguous, worst |error| %.3g\n",
      c.patch_size, c.sigma_color, result.num_valid, result.num_nan, result.num_ambiguous,
      result.worst_error);
  // Both outcomes exercised, and border ambiguity stays rare.
  EXPECT_GT(result.num_valid, static_cast<int>(pairs.size()) / 4);
  EXPECT_GT(result.num_nan, static_cast<int>(pairs.size()) / 10);
  EXPECT_LE(result.num_ambiguous, static_cast<int>(pairs.size()) / 200);
}

INSTANTIATE_TEST_SUITE_P(NccSizes, NccScorerCaseTest,
                         ::testing::Values(ScoreCase{5, 161, 123, 31}, ScoreCase{7, 161, 123, 32},
                                           ScoreCase{11, 161, 123, 33}, ScoreCase{7, 97, 211, 34},
                                           ScoreCase{11, 255, 101, 35},
                                           // Sample weights: the matcher's default and
                                           // narrower.
                                           ScoreCase{7, 161, 123, 36, 3.0},
                                           ScoreCase{5, 97, 211, 37, 1.0},
                                           ScoreCase{15, 201, 161, 38, 3.0}),
                         ScoreCaseName);

class NccScorerTest : public ClTest {};

// A group whose images lie in one host block at the buffer's offsets (as
// LoadMatchGroup packs them): a device sharing the host's memory reads the
// block in place, and scores exactly as from a copy; a group whose images
// do not lie so is copied.
TEST_F(NccScorerTest, ImagesInOneHostBlockAreReadInPlaceAndScoreAsACopy) {
  const PlaneScene scene = MakePlaneScene(3, 97, 61, 52);
  size_t total = 0;
  for (const FloatImageView& v : scene.group.images) total += v.layout.RequiredElements();
  std::shared_ptr<float> block(new float[total], std::default_delete<float[]>());
  NccGroup packed = scene.group;
  size_t offset = 0;
  for (FloatImageView& v : packed.images) {
    std::copy(v.data, v.data + v.layout.RequiredElements(), block.get() + offset);
    v.data = block.get() + offset;
    offset += v.layout.RequiredElements();
  }
  packed.pixels = block;
  const double device_before = DeviceBytesInUse();
  const NccDeviceGroup device = UploadNccGroup(context(), packed);
  const double image_bytes = static_cast<double>(total * sizeof(float));
  if (context().device().host_unified_memory) {
    EXPECT_EQ(device.pixels.get(), block.get());
    EXPECT_LT(DeviceBytesInUse() - device_before, image_bytes)
        << "the images read in place are not device memory of its own";
    void* host = nullptr;
    ASSERT_EQ(clGetMemObjectInfo(device.images.get(), CL_MEM_HOST_PTR, sizeof host, &host, nullptr),
              CL_SUCCESS);
    EXPECT_EQ(host, static_cast<void*>(block.get()));
  } else {
    EXPECT_EQ(device.pixels, nullptr) << "a device with memory of its own gets a copy";
    EXPECT_GE(DeviceBytesInUse() - device_before, image_bytes);
  }
  // One image elsewhere: copied, whatever the device.
  NccGroup scattered = packed;
  scattered.images[1].data = scene.group.images[1].data;
  EXPECT_EQ(UploadNccGroup(context(), scattered).pixels, nullptr);

  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  RandomBatch(scene, 120, 53, &patches, &pairs);
  NccScorer copied(context()), in_place(context());
  copied.SetGroup(scene.group);
  in_place.SetGroup(packed);
  const std::vector<float> a = copied.Score(patches, pairs);
  const std::vector<float> b = in_place.Score(patches, pairs);
  ASSERT_EQ(a.size(), b.size());
  int valid = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) {
      EXPECT_TRUE(std::isnan(b[i])) << "pair " << i;
    } else {
      EXPECT_EQ(a[i], b[i]) << "pair " << i;
      ++valid;
    }
  }
  EXPECT_GT(valid, static_cast<int>(a.size()) / 4);
}

// The geometry check: the true patch is photo-consistent in every view, the
// same patch slid along the reference ray is not.
TEST_F(NccScorerTest, TruePatchScoresHighAndOffsetPatchLow) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 41);
  const Camera& ref = scene.cameras[0];
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> truths;
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(80, 61), Eigen::Vector2d(72, 56),
                                    Eigen::Vector2d(88, 66), Eigen::Vector2d(84, 57)}) {
    const Eigen::Vector3d truth = GroundAt(ref, uv);
    truths.push_back(truth);
    const Eigen::Vector3d ray = (truth - ref.center()).normalized();
    for (double offset : {0.0, 8.0}) {
      const int p = static_cast<int>(patches.size());
      patches.push_back(MakeNccPatch(truth + offset * ray, normal, 0));
      for (int v = 1; v < 4; ++v) pairs.push_back({p, v});
    }
  }
  NccScorer scorer(context());
  scorer.SetGroup(scene.group);
  const std::vector<float> scores = scorer.Score(patches, pairs);
  std::vector<double> margin;
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, kDefaultPatchSize, &margin);
  int num_shifted = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_TRUE(NearAbsRel(scores[i], expected[i], kAbsTol, kRelTol)) << "pair " << i;
    ASSERT_FALSE(std::isnan(scores[i])) << "pair " << i << " should be inside every image";
    const NccPatch& patch = patches[pairs[i].patch];
    if (pairs[i].patch % 2 == 0) {
      EXPECT_GT(scores[i], 0.95) << "true patch, pair " << i;
      continue;
    }
    // How far the wrong depth moves the patch centre in this view, in pixels.
    const Camera& view = scene.cameras[pairs[i].view];
    const Eigen::Vector3d wrong(patch.center.s[0], patch.center.s[1], patch.center.s[2]);
    const Eigen::Vector3d& truth = truths[pairs[i].patch / 2];
    const double shift = (view.Project(wrong) - view.Project(truth)).norm();
    std::printf("[ NCC      ] pair %zu: true patch %.3f, offset patch %.3f, shift %.2f px\n", i,
                scores[i - 3], scores[i], shift);
    if (shift >= 3.0) {
      ++num_shifted;
      EXPECT_LT(scores[i], 0.6) << "patch off the surface along the ray, pair " << i;
      EXPECT_LT(scores[i], scores[i - 3] - 0.3) << "pair " << i;
    }
  }
  EXPECT_GE(num_shifted, 4);
  // The reference pairs with itself: NCC 1.
  const std::vector<float> self = scorer.Score(patches, {{0, 0}});
  EXPECT_NEAR(self[0], 1.0f, 1e-5f);
}

// A window whose right two columns lie, in the reference, on another
// surface (a bright roof edge overhanging the ground there, which the views
// see further right), at `contrast` times the scene's grey levels about 128;
// its patches on the ground under 3 such windows, each with the 3 views.
struct EdgeScene {
  PlaneScene scene;
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  // Plain and weighted (sigma_color 3) scores of the pairs, and the double
  // reference of the weighted.
  std::vector<float> plain, weighted;
  std::vector<double> expected;
};

EdgeScene ScoreEdgeScene(ClContext& context, double contrast) {
  EdgeScene e{MakePlaneScene(4, 161, 123, 81), {}, {}, {}, {}, {}};
  const Camera& ref = e.scene.cameras[0];
  const double edge = 80.25;  // reference column where the other surface starts
  const int width = 161, height = 123;
  std::mt19937 rng(82);
  std::uniform_real_distribution<float> noise(-20.0f, 20.0f);
  for (int i = 0; i < 4; ++i) {
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const Eigen::Vector2d uv(u, v);
        // The views see the other surface only 3 reference columns further on.
        const double u_ref = i == 0 ? u : ref.Project(GroundAt(e.scene.cameras[i], uv)).x();
        float& pixel = e.scene.pixels[i][static_cast<size_t>(v) * width + u];
        if (u_ref > edge + (i == 0 ? 0.0 : 3.0)) pixel = 240.0f + noise(rng);
        pixel = static_cast<float>(128.0 + contrast * (pixel - 128.0));
      }
    }
  }
  for (const double v : {40.0, 60.0, 80.0}) {
    e.patches.push_back(
        MakeNccPatch(GroundAt(ref, Eigen::Vector2d(79, v)), Eigen::Vector3d::UnitZ(), 0));
    for (int view = 1; view < 4; ++view)
      e.pairs.push_back({static_cast<int>(e.patches.size()) - 1, view});
  }
  NccScorerOptions weighted_options;
  weighted_options.sigma_color = 3.0;
  NccScorer plain(context, NccScorerOptions());
  NccScorer weighted(context, weighted_options);
  plain.SetGroup(e.scene.group);
  weighted.SetGroup(e.scene.group);
  e.plain = plain.Score(e.patches, e.pairs);
  e.weighted = weighted.Score(e.patches, e.pairs);
  e.expected = NccScoreReference(e.scene.group, e.patches, e.pairs, kDefaultPatchSize, nullptr,
                                 weighted_options.sigma_color);
  return e;
}

// Plain NCC fails on the ground the centre lies on; with sample weights the
// bright columns drop out and the ground matches. The weights scale from the
// spread of the centre's 3 x 3 samples, at least kNccWeightMinSpread grey
// levels: at 2 % contrast (the step to the other surface 2.2 grey levels,
// the texture's spread at a centre well under 1: weak texture, where the
// spread is the images' noise) the scene scores as plain NCC. Without the
// floor weights and NCC do not change with contrast.
TEST_F(NccScorerTest, SampleWeightsScoreTheSurfaceUnderTheCentreAboveTheNoise) {
  for (const double contrast : {1.0, 0.02}) {
    const EdgeScene e = ScoreEdgeScene(context(), contrast);
    for (size_t i = 0; i < e.pairs.size(); ++i) {
      const float p = e.plain[i], w = e.weighted[i];
      std::printf("[ NCC      ] contrast %g, pair %zu: plain %.3f, weighted %.3f\n", contrast, i, p,
                  w);
      // Measured: plain -0.33 to 0.42, weighted 0.64 to 0.97 at full contrast.
      EXPECT_LT(p, 0.5) << "pair " << i;
      if (contrast == 1.0) {
        EXPECT_GT(w, 0.6) << "pair " << i;
        EXPECT_GT(w, p + 0.4) << "pair " << i;
      } else {
        EXPECT_LT(std::abs(w - p), 0.1) << "pair " << i;
      }
      EXPECT_TRUE(NearAbsRel(w, e.expected[i], kAbsTol, kRelTol)) << "pair " << i;
    }
  }
}

TEST_F(NccScorerTest, FlatImageAndBehindCameraGiveNaN) {
  PlaneScene scene = MakePlaneScene(3, 61, 47, 51);
  // Image 2: image 0's camera over a flat image, so only the variance rule
  // can void its pairs.
  std::fill(scene.pixels[2].begin(), scene.pixels[2].end(), 200.0f);
  scene.group.cameras[2] = scene.group.cameras[0];
  const Eigen::Vector3d truth = GroundAt(scene.cameras[0], Eigen::Vector2d(30, 23));
  std::vector<NccPatch> patches = {
      MakeNccPatch(truth, Eigen::Vector3d::UnitZ(), 0),
      // Far above every camera: in front of none of them.
      MakeNccPatch(truth + Eigen::Vector3d(0, 0, 100), Eigen::Vector3d::UnitZ(), 0),
      // A plane perpendicular to the reference x axis: no in-plane grid.
      MakeNccPatch(truth, scene.cameras[0].rotation().row(0).transpose(), 0)};
  const std::vector<NccPair> pairs = {{0, 0}, {0, 2}, {1, 0}, {2, 0}};
  NccScorer scorer(context());
  scorer.SetGroup(scene.group);
  const std::vector<float> scores = scorer.Score(patches, pairs);
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, kDefaultPatchSize);
  EXPECT_FALSE(std::isnan(scores[0]));
  for (size_t i = 1; i < pairs.size(); ++i) {
    EXPECT_TRUE(std::isnan(scores[i])) << "pair " << i;
    EXPECT_TRUE(std::isnan(expected[i])) << "pair " << i;
  }
}

// A NaN pixel under a view's window voids the pair also where the window
// lies wholly inside the view, whose samples sample_view (ncc.cl) reads
// without checking them one by one: at the window's centre and at its corner
// sample. The untouched patch keeps its score.
TEST_F(NccScorerTest, NaNPixelVoidsThePairInsideTheImage) {
  PlaneScene scene = MakePlaneScene(2, 161, 123, 61);
  const Camera& ref = scene.cameras[0];
  const Camera& view = scene.cameras[1];
  const int half = kDefaultPatchSize / 2;
  // Patch centre in the reference, and the reference offset whose ground
  // point gets the NaN pixels in the view (none for the last patch).
  const std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> cases = {
      {{60, 50}, {0, 0}}, {{100, 70}, {half, half}}, {{80, 40}, {kNaN, kNaN}}};
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  for (const auto& [uv, offset] : cases) {
    const Eigen::Vector3d center = GroundAt(ref, uv);
    patches.push_back(MakeNccPatch(center, Eigen::Vector3d::UnitZ(), 0));
    pairs.push_back({static_cast<int>(patches.size()) - 1, 1});
    if (std::isnan(offset.x())) continue;
    const Eigen::Vector2d at = view.Project(GroundAt(ref, uv + offset));
    ASSERT_TRUE(view.InImage(at, 2 * half + 2)) << at.transpose();
    // The whole 2 x 2 support of the sample.
    for (int dy = 0; dy <= 1; ++dy) {
      for (int dx = 0; dx <= 1; ++dx) {
        const int x = static_cast<int>(std::floor(at.x())) + dx;
        const int y = static_cast<int>(std::floor(at.y())) + dy;
        scene.pixels[1][static_cast<size_t>(y) * view.width() + x] = kNaN;
      }
    }
  }
  NccScorer scorer(context());
  scorer.SetGroup(scene.group);
  const std::vector<float> scores = scorer.Score(patches, pairs);
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, kDefaultPatchSize);
  ASSERT_EQ(scores.size(), 3u);
  EXPECT_TRUE(std::isnan(scores[0]));
  EXPECT_TRUE(std::isnan(scores[1]));
  EXPECT_TRUE(std::isnan(expected[0]));
  EXPECT_TRUE(std::isnan(expected[1]));
  EXPECT_GT(scores[2], 0.9f);
  EXPECT_TRUE(NearAbsRel(scores[2], expected[2], kAbsTol, kRelTol));
}

// The grid spans the same reference pixels however the plane is tilted (as
// PMVS2's getPAxes): a patch 5 px below the top border, its plane turned
// about the reference x axis away from facing the camera, keeps its top
// samples 3 rows above its centre, 2 px from the border (the reference scored
// against itself, so the margin is the reference's). A grid stepping a
// face-on footprint along the plane would keep them at 3 cos(tilt) rows: at
// 70 degrees a margin near 4 px. Beyond 84 degrees the plane is not scored.
TEST_F(NccScorerTest, ObliquePlaneKeepsItsReferenceWindow) {
  const PlaneScene scene = MakePlaneScene(2, 161, 123, 91);
  const Camera& ref = scene.cameras[0];
  const Eigen::Vector3d center = GroundAt(ref, Eigen::Vector2d(80, 5));
  const Eigen::Vector3d facing = (ref.center() - center).normalized();
  const Eigen::Vector3d ref_x = ref.rotation().row(0).transpose();
  const std::vector<double> tilts = {0.0, 40.0, 70.0, 80.0, 86.0};
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  for (const double tilt : tilts) {
    const Eigen::Vector3d normal =
        Eigen::AngleAxisd(ToRadians(tilt, AngleUnit::kDegree), ref_x) * facing;
    pairs.push_back({static_cast<int>(patches.size()), 0});
    patches.push_back(MakeNccPatch(center, normal, 0));
  }
  std::vector<double> margin;
  const std::vector<double> expected =
      NccScoreReference(scene.group, patches, pairs, kDefaultPatchSize, &margin);
  NccScorer scorer(context());
  scorer.SetGroup(scene.group);
  const std::vector<float> scores = scorer.Score(patches, pairs);
  for (size_t i = 0; i < tilts.size(); ++i) {
    std::printf("[ NCC      ] tilt %.0f deg: margin %.3f px, score %.3f\n", tilts[i], margin[i],
                scores[i]);
    EXPECT_TRUE(NearAbsRel(scores[i], expected[i], kAbsTol, kRelTol)) << "tilt " << tilts[i];
    if (tilts[i] > 84.0) {
      EXPECT_TRUE(std::isnan(expected[i])) << "tilt " << tilts[i];
      continue;
    }
    ASSERT_FALSE(std::isnan(expected[i])) << "tilt " << tilts[i];
    EXPECT_NEAR(expected[i], 1.0, 1e-9) << "tilt " << tilts[i];
    // The window is the reference's pixels around the centre whatever the
    // tilt: its top row lies exactly 2 px from the border. Axes on the plane
    // scaled at the centre left 1.98, 1.91, 1.79 and 1.61 px (perspective
    // bends the tilted plane's rows), a face-on footprint step 2.0, 2.7, 4.0
    // and 4.5.
    EXPECT_NEAR(margin[i], 2.0, 1e-3) << "tilt " << tilts[i];
  }
}

// Neither the work-group size nor the order of the pairs changes a score.
// The kernel gives each run of consecutive pairs of one patch to one
// work-item, which samples the reference window once: grouped by patch (runs
// of 3) and shuffled (runs of 1 mostly) must give the same floats.
TEST_F(NccScorerTest, BatchLayoutDoesNotChangeResults) {
  const PlaneScene scene = MakePlaneScene(3, 97, 61, 61);
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  RandomBatch(scene, 77, 62, &patches, &pairs);
  NccScorer base(context());
  base.SetGroup(scene.group);
  const std::vector<float> reference = base.Score(patches, pairs);
  auto same = [](float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  for (int group : {1, 7, 32}) {
    NccScorerOptions options;
    options.work_group_size = group;
    NccScorer scorer(context(), options);
    scorer.SetGroup(scene.group);
    const std::vector<float> scores = scorer.Score(patches, pairs);
    for (size_t i = 0; i < scores.size(); ++i) {
      ASSERT_TRUE(same(scores[i], reference[i])) << "work-group size " << group << ", pair " << i;
    }
  }
  std::vector<size_t> order(pairs.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  std::vector<NccPair> shuffled;
  for (const size_t i : order) shuffled.push_back(pairs[i]);
  const std::vector<float> scores = base.Score(patches, shuffled);
  int valid = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    ASSERT_TRUE(same(scores[k], reference[order[k]])) << "shuffled, pair " << order[k];
    valid += !std::isnan(scores[k]);
  }
  EXPECT_GT(valid, 50);  // scored pairs are compared, not NaNs only
}

// ncc.cl samples through bilinear.cl, the primitive bilinear_sample.cl
// exposes; through the packed image table it must still match
// BilinearSampleReference.
TEST_F(NccScorerTest, PackedBilinearMatchesBilinearReference) {
  // Two images with row padding (NaN, so reading it shows), the second at a
  // non-zero offset in the packed buffer.
  std::mt19937 rng(71);
  std::uniform_real_distribution<float> value(0.0f, 255.0f);
  const ImageLayout layouts[2] = {{13, 7, 16}, {9, 11, 10}};
  std::vector<std::vector<float>> pixels;
  NccGroup group;
  for (const ImageLayout& layout : layouts) {
    std::vector<float> image(layout.RequiredElements(), kNaN);
    for (int r = 0; r < layout.height; ++r) {
      for (int c = 0; c < layout.width; ++c)
        image[static_cast<size_t>(r) * layout.row_pitch + c] = value(rng);
    }
    pixels.push_back(std::move(image));
  }
  const Camera camera(Intrinsics::FromPixels(10, 10, 4, 3, 13, 7), Eigen::Matrix3d::Identity(),
                      Eigen::Vector3d::Zero());
  for (int i = 0; i < 2; ++i) {
    group.images.push_back({pixels[i].data(), layouts[i]});
    group.cameras.push_back(MakeNccCamera(camera));
  }
  NccScorer scorer(context());
  scorer.SetGroup(group);
  for (int i = 0; i < 2; ++i) {
    const float w = static_cast<float>(layouts[i].width - 1);
    const float h = static_cast<float>(layouts[i].height - 1);
    std::uniform_real_distribution<float> x(-1.0f, w + 1.0f);
    std::uniform_real_distribution<float> y(-1.0f, h + 1.0f);
    std::vector<Eigen::Vector2f> points = {{0, 0},         {w, h},      {w, 0},        {0, h},
                                           {w + 1e-3f, 0}, {0, -1e-3f}, {0.5f * w, h}, {kNaN, 1}};
    for (int k = 0; k < 300; ++k) points.emplace_back(x(rng), y(rng));
    const std::vector<float> values = scorer.ProbeSamples(i, points);
    int num_nan = 0;
    for (size_t k = 0; k < points.size(); ++k) {
      const double expected =
          BilinearSampleReference(group.images[i], points[k].x(), points[k].y());
      EXPECT_TRUE(NearAbsRel(values[k], expected, 4 * 255 * 1.2e-7, 4 * 1.2e-7))
          << "image " << i << " at (" << points[k].x() << ", " << points[k].y() << ")";
      num_nan += std::isnan(expected) ? 1 : 0;
    }
    EXPECT_GT(num_nan, 0);
  }
}

}  // namespace
}  // namespace sapmvs

#include "match/patch_engine.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <set>
#include <tuple>
#include <vector>

#include "cl_test_fixture.h"
#include "device/cl_patch_kernels.h"
#include "match/group_data.h"
#include "plane_scene.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/thread_count.h"

namespace sapmvs {
namespace {

using test::ClTest;
using test::GroundAt;
using test::MakePlaneScene;
using test::PlaneScene;

constexpr double kPiRad = 3.14159265358979323846;

double Footprint(const Camera& camera, const Eigen::Vector3d& x) {
  return camera.Depth(x) / camera.intrinsics().MeanFocal();
}

// Seeds in image 0 from test::PerturbedStarts.
std::vector<PatchCandidate> TiltedSeeds(const PlaneScene& scene, int count, double depth_offset,
                                        double tilt_deg, uint32_t seed) {
  std::vector<PatchCandidate> seeds;
  for (const test::PlaneStart& s :
       test::PerturbedStarts(scene, count, depth_offset, tilt_deg, {25.0, 20.0}, seed)) {
    PatchCandidate c;
    c.center = s.center;
    c.normal = s.normal;
    c.ref = 0;
    seeds.push_back(c);
  }
  return seeds;
}

class PatchEngineTest : public ClTest {
 protected:
  // A backend per engine: an engine holds its group on its backend until it
  // is destroyed, and some tests keep two engines.
  PatchKernels& NewKernels() {
    kernels_.push_back(MakeClPatchKernels(context()));
    return *kernels_.back();
  }

 private:
  std::vector<std::unique_ptr<PatchKernels>> kernels_;
};

// On flat textured ground every seed grows to the largest adaptive size,
// from a 7 x 7 start whose normal is a few degrees off: the unpolished plane
// must pass the test before polishing (threshold_before, whole window and
// border sub-windows), and the polish must bring the normal back to within
// a degree or two, or the border sub-windows fail threshold.
TEST_F(PatchEngineTest, FlatGroundGrowsToTheLargestSizeFromATiltedStart) {
  const PlaneScene scene = MakePlaneScene(4, 201, 161, 91);
  const MatchGroupData group = test::MatchGroupOf(scene);
  MatcherOptions options;  // sapmvs mode, sizes 21, 15, 11, 7
  ASSERT_EQ(options.adaptive_sizes.front(), 21);
  // The scene's cameras are a few metres apart at 40 m: growth needs a view
  // 2 max_angle from the reference (WorthPolishing), so 5 degrees here.
  options.max_angle_deg = 5.0;
  PatchEngine engine(NewKernels(), group, options);
  const std::vector<PatchCandidate> seeds = TiltedSeeds(scene, 12, 1.0, 6.0, 92);
  const auto results = engine.Evaluate(seeds);
  ASSERT_EQ(results.size(), seeds.size());
  const Camera& ref = scene.cameras[0];
  int largest = 0;
  for (size_t i = 0; i < results.size(); ++i) {
    ASSERT_TRUE(results[i]) << "seed " << i << " rejected";
    const AcceptedPatch& a = *results[i];
    const Eigen::Vector3d truth = GroundAt(ref, ref.Project(a.center));
    const double depth_error =
        std::abs(ref.Depth(a.center) - ref.Depth(truth)) / Footprint(ref, truth);
    const double normal_error =
        std::acos(std::clamp(a.normal.normalized().z(), -1.0, 1.0)) * 180.0 / kPiRad;
    std::printf(
        "[ ENGINE   ] seed %zu: size %d, depth error %.3f footprints, normal %.2f deg, "
        "score %.4f, %zu views\n",
        i, a.size, depth_error, normal_error, a.score, a.views.size());
    EXPECT_LT(depth_error, 0.25) << "seed " << i;
    EXPECT_LT(normal_error, 2.0) << "seed " << i;
    EXPECT_GE(a.score, options.threshold) << "seed " << i;
    EXPECT_GE(static_cast<int>(a.views.size()), options.min_image_num - 1) << "seed " << i;
    if (a.size == options.adaptive_sizes.front()) ++largest;
  }
  EXPECT_EQ(largest, static_cast<int>(seeds.size()));
  // The same seeds in pmvs mode stay 7 x 7 (no adaptive sizes).
  options.mode = MatchMode::kPmvs;
  PatchEngine pmvs(NewKernels(), group, options);
  for (const auto& r : pmvs.Evaluate(seeds)) {
    ASSERT_TRUE(r);
    EXPECT_EQ(r->size, options.window_size);
  }
}

// Forwards to a backend and records the options of every launch.
class RecordingKernels : public PatchKernels {
 public:
  explicit RecordingKernels(PatchKernels& inner) : inner_(inner) {}
  const KernelDevice& device() const override { return inner_.device(); }
  void SetGroup(const NccGroup& group) override { inner_.SetGroup(group); }
  void ClearGroup() override { inner_.ClearGroup(); }
  std::vector<float> Score(const NccScorerOptions& options, const std::vector<NccPatch>& patches,
                           const std::vector<NccPair>& pairs, double* seconds) override {
    scorers.push_back(options);
    return inner_.Score(options, patches, pairs, seconds);
  }
  std::vector<RefinedPatch> Refine(const PatchRefinerOptions& options,
                                   const std::vector<NccPatch>& patches,
                                   const std::vector<std::vector<int>>& views,
                                   double* seconds) override {
    refiners.push_back(options);
    return inner_.Refine(options, patches, views, seconds);
  }
  std::vector<NccScorerOptions> scorers;
  std::vector<PatchRefinerOptions> refiners;

 private:
  PatchKernels& inner_;
};

auto KeyOf(const NccScorerOptions& o) {
  return std::make_tuple(o.patch_size, o.work_group_size, o.sigma_color, o.sample_step);
}
auto KeyOf(const PatchRefinerOptions& o) {
  return std::make_tuple(o.patch_size, o.work_group_size, o.iterations, o.max_halvings,
                         o.depth_step, o.angle_step_deg, o.max_angle_deg, o.sigma_color,
                         o.sample_step);
}

// The distinct variants among `launched` (-1 when one is not in `variants`).
template <typename Options>
int VariantsWithin(const std::vector<Options>& launched, const std::vector<Options>& variants) {
  std::set<decltype(KeyOf(Options{}))> used, prepared;
  for (const Options& o : variants) prepared.insert(KeyOf(o));
  for (const Options& o : launched) {
    if (!prepared.count(KeyOf(o))) return -1;
    used.insert(KeyOf(o));
  }
  return static_cast<int>(used.size());
}

// MatchGroup builds EngineKernelVariants' programs ahead of the engines
// (PatchKernels::Prepare): they must launch none other, in either mode. Here
// every seed grows to 21 x 21, so sapmvs mode launches the 7 x 7 and the
// 21 x 21 variants (and would the others for seeds that stop between), and
// its pmvs passes' engine (PmvsPassOptions) its own 7 x 7 ones.
TEST_F(PatchEngineTest, LaunchesOnlyTheVariantsPreparedForIt) {
  const PlaneScene scene = MakePlaneScene(4, 201, 161, 91);
  const MatchGroupData group = test::MatchGroupOf(scene);
  MatcherOptions options;
  options.max_angle_deg = 5.0;  // as above
  for (const MatchMode mode : {MatchMode::kSapmvs, MatchMode::kPmvs}) {
    options.mode = mode;
    RecordingKernels kernels(NewKernels());
    const bool sapmvs = mode == MatchMode::kSapmvs;
    {
      PatchEngine engine(kernels, group, options);
      engine.Evaluate(TiltedSeeds(scene, 12, 1.0, 6.0, 92));
    }
    const MatcherOptions pmvs_pass = PmvsPassOptions(options);
    if (sapmvs) {
      PatchEngine engine(kernels, group, pmvs_pass);
      engine.Evaluate(TiltedSeeds(scene, 12, 1.0, 6.0, 93));
    }
    const EngineKernels variants = EngineKernelVariants(options);
    EXPECT_EQ(variants.scorers.size(), sapmvs ? 5u : 1u);
    EXPECT_EQ(variants.refiners.size(), sapmvs ? 5u : 1u);
    EXPECT_EQ(VariantsWithin(kernels.scorers, variants.scorers), sapmvs ? 3 : 1);
    EXPECT_EQ(VariantsWithin(kernels.refiners, variants.refiners), sapmvs ? 3 : 1);
    // None of them without pmvs passes.
    MatcherOptions adaptive_only = options;
    adaptive_only.pmvs_passes = 0;
    EXPECT_EQ(EngineKernelVariants(adaptive_only).scorers.size(), sapmvs ? 4u : 1u);
  }
}

// A batch large enough to be evaluated as two halves on two threads gets,
// candidate by candidate, the results its pieces get one small batch at a
// time: the halves neither mix up nor reorder results, and accepted and
// rejected candidates are spread over both halves.
TEST_F(PatchEngineTest, ALargeBatchGetsTheResultsItsPiecesGetAlone) {
  const PlaneScene scene = MakePlaneScene(4, 201, 161, 91);
  const MatchGroupData group = test::MatchGroupOf(scene);
  MatcherOptions options;
  options.max_angle_deg = 5.0;  // as above, so that patches grow
  const std::vector<PatchCandidate> good = TiltedSeeds(scene, 400, 1.0, 6.0, 101);
  const std::vector<PatchCandidate> away = TiltedSeeds(scene, 400, 0.0, 80.0, 102);
  std::vector<PatchCandidate> batch;
  for (size_t i = 0; i < good.size(); ++i) {
    batch.push_back(good[i]);
    if (i % 3 == 0) batch.push_back(away[i]);
  }
  PatchEngine whole(NewKernels(), group, options);
  const auto results = whole.Evaluate(batch);
  PatchEngine pieces(NewKernels(), group, options);
  std::vector<std::optional<AcceptedPatch>> expected;
  for (size_t b = 0; b < batch.size(); b += 100) {
    const std::vector<PatchCandidate> piece(batch.begin() + b,
                                            batch.begin() + std::min(batch.size(), b + 100));
    for (auto& r : pieces.Evaluate(piece)) expected.push_back(std::move(r));
  }
  ASSERT_EQ(results.size(), batch.size());
  ASSERT_EQ(expected.size(), batch.size());
  int accepted = 0;
  for (size_t i = 0; i < batch.size(); ++i) {
    ASSERT_EQ(results[i].has_value(), expected[i].has_value()) << "candidate " << i;
    if (!results[i]) continue;
    ++accepted;
    EXPECT_EQ(results[i]->center, expected[i]->center) << "candidate " << i;
    EXPECT_EQ(results[i]->normal, expected[i]->normal) << "candidate " << i;
    EXPECT_EQ(results[i]->score, expected[i]->score) << "candidate " << i;
    EXPECT_EQ(results[i]->size, expected[i]->size) << "candidate " << i;
    EXPECT_EQ(results[i]->views, expected[i]->views) << "candidate " << i;
  }
  EXPECT_GT(accepted, 300);
  EXPECT_LT(accepted, static_cast<int>(batch.size()) - 100);
  // Two halves, one 7 x 7 refinement each, where there are two host threads.
  const int halves = HostThreadCount() >= 2 ? 2 : 1;
  EXPECT_EQ(whole.kernel_times().at("patch_refine 7x7").launches, halves);
}

// Seeds on the ground are rejected when fewer than min_image_num - 1 other
// images see them (here more than the scene has), and seeds whose plane
// faces away from the reference image are never scored.
TEST_F(PatchEngineTest, RejectsSeedsWithTooFewViewsOrFacingAway) {
  const PlaneScene scene = MakePlaneScene(4, 201, 161, 93);
  const MatchGroupData group = test::MatchGroupOf(scene);
  MatcherOptions options;
  {
    PatchEngine engine(NewKernels(), group, options);
    const std::vector<PatchCandidate> away = TiltedSeeds(scene, 4, 0.0, 80.0, 95);
    for (const auto& r : engine.Evaluate(away)) EXPECT_FALSE(r);
    const std::vector<PatchCandidate> good = TiltedSeeds(scene, 4, 0.0, 0.0, 94);
    for (const auto& r : engine.Evaluate(good)) EXPECT_TRUE(r);
  }
  options.min_image_num = 5;
  PatchEngine engine(NewKernels(), group, options);
  for (const auto& r : engine.Evaluate(TiltedSeeds(scene, 4, 0.0, 0.0, 94))) EXPECT_FALSE(r);
}

// Another strip's images (view-only, ImageGroup::views) only bring a
// patch's views among the group's own images up to min_image_num: with
// min_image_num 3 a patch that two own images see takes one of them and no
// patch has more than 3 views; with min_image_num 5 a patch needs both, and
// is accepted only thanks to them.
TEST_F(PatchEngineTest, ViewOnlyImagesOnlyFillUpToMinImageNum) {
  const PlaneScene scene = MakePlaneScene(5, 201, 161, 97);
  MatchGroupData group = test::MatchGroupOf(scene);
  group.images[3].reference = group.images[4].reference = false;
  const std::vector<PatchCandidate> seeds = TiltedSeeds(scene, 6, 0.0, 0.0, 98);
  auto view_only = [](const AcceptedPatch& a) {
    return std::count_if(a.views.begin(), a.views.end(), [](int v) { return v >= 3; });
  };
  MatcherOptions options;
  {
    PatchEngine engine(NewKernels(), group, options);
    int with_one = 0;
    for (const auto& r : engine.Evaluate(seeds)) {
      ASSERT_TRUE(r);
      EXPECT_LE(r->views.size(), 3u);
      with_one += view_only(*r) == 1;
    }
    EXPECT_GT(with_one, 0);
  }
  options.min_image_num = 5;
  PatchEngine engine(NewKernels(), group, options);
  int accepted = 0;
  for (const auto& r : engine.Evaluate(seeds)) {
    if (!r) continue;
    ++accepted;
    EXPECT_EQ(view_only(*r), 2);
  }
  EXPECT_GT(accepted, 0);
  // Without them, 3 images cannot give 4 views.
  MatchGroupData own = group;
  for (MatchImage& im : own.images) {
    im.views.erase(std::remove_if(im.views.begin(), im.views.end(), [](int v) { return v >= 3; }),
                   im.views.end());
  }
  PatchEngine without(NewKernels(), own, options);
  for (const auto& r : without.Evaluate(seeds)) EXPECT_FALSE(r);
}

// A reference keeps its group's own images before another strip's
// view-only ones when more than kMaxViews - 1 images overlap it: view-only
// images only fill (PatchEngine::VisibleViews). Ten images 1 m apart at 40 m
// all overlap image 0 well beyond SelectViews' 10 %; by overlap alone its
// nearest neighbours, 1 and 2, would be kept and two of its own dropped.
TEST(SelectViewsTest, OwnImagesComeBeforeViewOnlyOnes) {
  const PlaneScene strip = MakePlaneScene(10, 201, 161, 99, 1.0);
  for (const int view_only : {2, 3}) {
    MatchGroupData group = test::MatchGroupOf(strip);
    for (MatchImage& im : group.images) im.depth = 40.0;
    for (int i = 1; i <= view_only; ++i) group.images[i].reference = false;
    SelectViews(MatcherOptions(), &group);
    const std::vector<int>& views = group.images[0].views;
    ASSERT_EQ(views.size(), static_cast<size_t>(kMaxViews - 1));
    int own = 0;
    for (const int v : views) own += group.images[v].reference;
    // 7 own images with 2 view-only; with 3, the 6 own and then one of the others.
    EXPECT_EQ(own, view_only == 2 ? 7 : 6) << view_only << " view-only";
    EXPECT_TRUE(group.images[views.back()].reference == (view_only == 2)) << view_only;
  }
}

// Where the group's own images meet too narrowly, a view-only image that
// widens the angle joins a patch's views, even when the reference's list
// (SelectViews) is full of its own: ten images 1.35 degrees apart along a
// strip, the eight own ones spanning 9.45 degrees (under max_angle), the
// two view-only ones at either end 10.8. Image 0's seven views are all its
// own, so without the view-only ones no patch of it is wide enough.
TEST_F(PatchEngineTest, AViewOnlyImageWidensWhereTheOwnImagesMeetTooNarrowly) {
  const double base = 40.0 * std::tan(1.35 * kPiRad / 180.0);
  const PlaneScene strip = MakePlaneScene(10, 201, 161, 96, base);
  MatchGroupData group = test::MatchGroupOf(strip);
  for (MatchImage& im : group.images) im.depth = 40.0;
  group.images[8].reference = group.images[9].reference = false;
  MatcherOptions options;
  ASSERT_EQ(options.max_angle_deg, 10.0);
  SelectViews(options, &group);
  ASSERT_EQ(group.images[0].views.size(), static_cast<size_t>(kMaxViews - 1));
  for (const int v : group.images[0].views) ASSERT_TRUE(group.images[v].reference) << v;
  PatchEngine engine(NewKernels(), group, options);
  int accepted = 0;
  for (const auto& r : engine.Evaluate(TiltedSeeds(strip, 8, 0.0, 0.0, 97))) {
    if (!r) continue;
    ++accepted;
    EXPECT_TRUE(std::any_of(r->views.begin(), r->views.end(), [](int v) { return v >= 8; }));
    EXPECT_LE(r->views.size(), static_cast<size_t>(kMaxViews - 1));
    const Camera& ref = strip.cameras[0];
    const Eigen::Vector3d truth = GroundAt(ref, ref.Project(r->center));
    EXPECT_LT(std::abs(ref.Depth(r->center) - ref.Depth(truth)) / Footprint(ref, truth), 0.5);
  }
  EXPECT_EQ(accepted, 8);
}

// The paper's narrow baselines: 5 images 4 degrees apart along a strip
// (2.8 m at 40 m). Every view of the middle image is narrower than
// max_angle (10 degrees), yet the views on either side of it are 12 to 16
// degrees apart, so patches are accepted (PMVS2's checkAngles); in a strip
// 0.5 degree apart, no pair of images reaches 10 degrees and every patch is
// rejected, however well it scores.
TEST_F(PatchEngineTest, NarrowViewsTakePartWhenSomePairIsWideEnough) {
  MatcherOptions options;
  options.mode = MatchMode::kPmvs;
  options.adaptive_sizes = {options.window_size};
  ASSERT_EQ(options.max_angle_deg, 10.0);
  const double base = 40.0 * std::tan(4.0 * kPiRad / 180.0);
  const PlaneScene strip = MakePlaneScene(5, 201, 161, 96, base);
  MatchGroupData group = test::MatchGroupOf(strip);
  for (MatchImage& im : group.images) im.depth = 40.0;
  SelectViews(options, &group);
  EXPECT_EQ(group.images[0].views.size(), 4u);  // none dropped for being narrow
  {
    PatchEngine engine(NewKernels(), group, options);
    int accepted = 0;
    for (const auto& r : engine.Evaluate(TiltedSeeds(strip, 8, 0.5, 3.0, 97))) {
      if (!r) continue;
      ++accepted;
      const Camera& ref = strip.cameras[0];
      const Eigen::Vector3d truth = GroundAt(ref, ref.Project(r->center));
      EXPECT_LT(std::abs(ref.Depth(r->center) - ref.Depth(truth)) / Footprint(ref, truth), 0.5);
    }
    EXPECT_EQ(accepted, 8);
  }
  // sapmvs mode: the views of image 0 are 4 and 8 degrees from it, under 2
  // max_angle, so its patches stay at window_size; with max_angle 3 they
  // grow.
  for (const double max_angle : {10.0, 3.0}) {
    MatcherOptions sapmvs;
    sapmvs.max_angle_deg = max_angle;
    PatchEngine engine(NewKernels(), group, sapmvs);
    int grown = 0, accepted = 0;
    for (const auto& r : engine.Evaluate(TiltedSeeds(strip, 8, 0.0, 0.0, 98))) {
      accepted += r.has_value();
      grown += r && r->size > sapmvs.window_size;
    }
    EXPECT_EQ(accepted, 8) << "max_angle " << max_angle;
    if (max_angle > 4) {
      EXPECT_EQ(grown, 0);
    }
    if (max_angle < 4) {
      EXPECT_GE(grown, 6);
    }
  }
  const PlaneScene narrow = MakePlaneScene(5, 201, 161, 96, 40.0 * std::tan(0.5 * kPiRad / 180.0));
  const MatchGroupData narrow_group = test::MatchGroupOf(narrow);
  PatchEngine engine(NewKernels(), narrow_group, options);
  for (const auto& r : engine.Evaluate(TiltedSeeds(narrow, 8, 0.0, 0.0, 97))) EXPECT_FALSE(r);
  // The same seeds pass once max_angle allows the pairs' 1 to 2 degrees.
  options.max_angle_deg = 0.8;
  PatchEngine lenient(NewKernels(), narrow_group, options);
  int accepted = 0;
  for (const auto& r : lenient.Evaluate(TiltedSeeds(narrow, 8, 0.0, 0.0, 97)))
    accepted += r.has_value();
  EXPECT_EQ(accepted, 8);
}

// A pmvs pass's one-cell patch needs a view at least 2 max_angle from its
// reference, where a patch of pmvs mode needs some pair of its images beyond
// max_angle: image 0's views are 4 and 8 degrees from it.
TEST_F(PatchEngineTest, OneCellPassPatchesNeedAViewTwiceMaxAngleFromTheReference) {
  const double base = 40.0 * std::tan(4.0 * kPiRad / 180.0);
  const PlaneScene strip = MakePlaneScene(5, 201, 161, 96, base);
  MatchGroupData group = test::MatchGroupOf(strip);
  for (MatchImage& im : group.images) im.depth = 40.0;
  MatcherOptions sapmvs;
  SelectViews(sapmvs, &group);
  auto accepted = [&](const MatcherOptions& options, PatchEngine::Role role) {
    PatchEngine engine(NewKernels(), group, options, role);
    int n = 0;
    for (const auto& r : engine.Evaluate(TiltedSeeds(strip, 8, 0.0, 0.0, 99))) n += r.has_value();
    return n;
  };
  MatcherOptions pass = PmvsPassOptions(sapmvs);
  ASSERT_EQ(pass.max_angle_deg, 10.0);
  EXPECT_EQ(accepted(pass, PatchEngine::Role::kPatches), 8);
  EXPECT_EQ(accepted(pass, PatchEngine::Role::kOneCellPass), 0);
  pass.max_angle_deg = 3.0;
  EXPECT_EQ(accepted(pass, PatchEngine::Role::kOneCellPass), 8);
}

// A pmvs pass's one-cell candidate whose parent's plane already scores
// kOneCellDepthOnlyScore in the views acceptance needs searches its depth
// alone: the accepted patch keeps the parent's normal, a few degrees off the
// ground's, and still finds the ground's depth. The same candidates refined
// as patches of pmvs mode turn their normals.
TEST_F(PatchEngineTest, OneCellCandidatesOnAPlaneThatHoldsKeepTheParentsNormal) {
  const PlaneScene scene = MakePlaneScene(4, 201, 161, 91);
  const MatchGroupData group = test::MatchGroupOf(scene);
  MatcherOptions sapmvs;
  MatcherOptions pass = PmvsPassOptions(sapmvs);
  pass.max_angle_deg = 2.0;  // the scene's views lie a few degrees apart
  std::vector<PatchCandidate> candidates = TiltedSeeds(scene, 10, 0.3, 4.0, 93);
  for (PatchCandidate& c : candidates) {
    c.has_parent = true;
    c.parent_center = c.center;
    c.parent_normal = c.normal;
    c.parent_score = 0.95f;
  }
  const Camera& ref = scene.cameras[0];
  auto turned_deg = [](const PatchCandidate& c, const AcceptedPatch& a) {
    const double cosine = std::clamp(a.normal.normalized().dot(c.normal.normalized()), -1.0, 1.0);
    return std::acos(cosine) * 180.0 / kPiRad;
  };
  int kept = 0, turned = 0;
  for (const PatchEngine::Role role :
       {PatchEngine::Role::kOneCellPass, PatchEngine::Role::kPatches}) {
    PatchEngine engine(NewKernels(), group, pass, role);
    const auto results = engine.Evaluate(candidates);
    ASSERT_EQ(results.size(), candidates.size());
    for (size_t i = 0; i < results.size(); ++i) {
      ASSERT_TRUE(results[i]) << "candidate " << i;
      const AcceptedPatch& a = *results[i];
      const Eigen::Vector3d truth = GroundAt(ref, ref.Project(a.center));
      EXPECT_LT(std::abs(ref.Depth(a.center) - ref.Depth(truth)) / Footprint(ref, truth), 0.25)
          << "candidate " << i;
      const double turn = turned_deg(candidates[i], a);
      if (role == PatchEngine::Role::kOneCellPass) {
        EXPECT_LT(turn, 1e-3) << "candidate " << i;
        kept += turn < 1e-3;
      } else {
        turned += turn > 0.5;
      }
    }
  }
  EXPECT_EQ(kept, static_cast<int>(candidates.size()));
  EXPECT_GE(turned, static_cast<int>(candidates.size()) / 2);
}

// A large window keeps its extent and loses samples: the fewest odd grid
// whose spacing stays at most the step asked for; the window size itself and
// anything smaller sample every pixel.
TEST(SampledWindowTest, SpansTheWindowWithTheFewestSamples) {
  const struct {
    int side;
    double max_step;
    int samples;
    double step;
  } cases[] = {{21, 2.0, 11, 2.0}, {15, 2.0, 9, 1.75},        {11, 2.0, 7, 5.0 / 3.0},
               {21, 1.0, 21, 1.0}, {21, 1.5, 15, 10.0 / 7.0}, {7, 2.0, 7, 1.0},
               {5, 2.0, 5, 1.0},   {21, 4.0, 7, 10.0 / 3.0}};
  for (const auto& c : cases) {
    const WindowGrid g = SampledWindow(c.side, 7, c.max_step);
    EXPECT_EQ(g.samples, c.samples) << c.side << " px at most " << c.max_step << " apart";
    EXPECT_NEAR(g.step, c.step, 1e-12) << c.side << " px at most " << c.max_step << " apart";
    EXPECT_EQ(g.samples % 2, 1);
    EXPECT_NEAR((g.samples - 1) * g.step, c.side <= 7 ? c.side - 1 : c.side - 1, 1e-9);
  }
}

}  // namespace
}  // namespace sapmvs

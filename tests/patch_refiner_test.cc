#include "device/patch_refiner.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "plane_scene.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {
namespace {

using test::ClTest;

constexpr double kPiRad = 3.14159265358979323846;

// Final mean NCC, kernel vs reference. Both run the same search; float32
// scores differ from the double ones by about 1e-5 (ncc_scorer_test), which
// can flip a near-tie late in the search and end on a neighbouring point of
// the same optimum, so the tolerance is on the score, not bit-level.
constexpr double kRefineScoreTol = 2e-3;
// Where every decision of the reference search had a margin above this, the
// kernel must take the same path; its parameters must then agree to float
// precision.
constexpr double kRefineSafeMargin = 1e-4;
constexpr double kRefineDepthTol = 1e-3;  // Footprints.
constexpr double kRefineAngleTol = 1e-4;  // Radians.

using test::MakePlaneScene;
using test::PlaneScene;

using test::GroundAt;

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / kPiRad;
}

// Footprint (depth / f) of `camera` at `x`.
double Footprint(const Camera& camera, const Eigen::Vector3d& x) {
  return (camera.rotation() * (x - camera.center())).z() / camera.intrinsics().MeanFocal();
}

// Patches on the ground near the centre of image 0 (test::PerturbedStarts),
// each matched with the three other images.
void PerturbedPatches(const PlaneScene& scene, int num_patches, double depth_offset,
                      double tilt_deg, uint32_t seed, std::vector<NccPatch>* patches,
                      std::vector<std::vector<int>>* views) {
  for (const test::PlaneStart& s :
       test::PerturbedStarts(scene, num_patches, depth_offset, tilt_deg, {20.0, 15.0}, seed)) {
    patches->push_back(MakeNccPatch(s.center, s.normal, 0));
    views->push_back({1, 2, 3});
  }
}

struct RefComparison {
  double worst_score_error = 0.0;
  double worst_depth_error = 0.0;
  double worst_angle_error = 0.0;
  int same_path = 0;
};

RefComparison CompareWithReference(const std::vector<RefinedPatch>& got,
                                   const std::vector<RefinedPatchReference>& expected) {
  RefComparison c;
  EXPECT_EQ(got.size(), expected.size());
  for (size_t i = 0; i < std::min(got.size(), expected.size()); ++i) {
    const RefinedPatch& g = got[i];
    const RefinedPatchReference& e = expected[i];
    EXPECT_EQ(std::isnan(g.score), std::isnan(e.score)) << "patch " << i;
    if (std::isnan(e.score) || std::isnan(g.score)) continue;
    EXPECT_NEAR(g.score, e.score, kRefineScoreTol) << "patch " << i;
    c.worst_score_error = std::max(c.worst_score_error, std::abs(g.score - e.score));
    if (e.decision_margin > kRefineSafeMargin) {
      ++c.same_path;
      EXPECT_EQ(g.moves, e.moves) << "patch " << i;
      EXPECT_EQ(g.evaluations, e.evaluations) << "patch " << i;
      EXPECT_NEAR(g.depth_offset, e.depth_offset, kRefineDepthTol) << "patch " << i;
      EXPECT_NEAR(g.yaw, e.yaw, kRefineAngleTol) << "patch " << i;
      EXPECT_NEAR(g.pitch, e.pitch, kRefineAngleTol) << "patch " << i;
      c.worst_depth_error =
          std::max(c.worst_depth_error, std::abs(g.depth_offset - e.depth_offset));
      c.worst_angle_error =
          std::max({c.worst_angle_error, std::abs(g.yaw - e.yaw), std::abs(g.pitch - e.pitch)});
      EXPECT_EQ(g.view_scores.size(), e.view_scores.size());
      for (size_t v = 0; v < std::min(g.view_scores.size(), e.view_scores.size()); ++v) {
        EXPECT_NEAR(g.view_scores[v], e.view_scores[v], 1e-4) << "patch " << i << " view " << v;
      }
    }
  }
  return c;
}

TEST(PatchRefinerOptionsTest, CheckRejectsBadValues) {
  EXPECT_TRUE(PatchRefinerOptions().Check());
  auto bad = [](auto mutate) {
    PatchRefinerOptions o;
    mutate(o);
    return !o.Check();
  };
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.patch_size = 4; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.patch_size = kMaxPatchSize + 2; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.work_group_size = 0; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.sample_step = 0.5; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.sample_step = kMaxSampleStep + 0.5; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.sample_step = std::nan(""); }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.iterations = -1; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.iterations = kMaxRefineIterations + 1; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.max_halvings = 0; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.depth_step = 0.0; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.depth_step = std::nan(""); }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.angle_step_deg = 60.0; }));
  EXPECT_TRUE(bad([](PatchRefinerOptions& o) { o.max_angle_deg = 90.0; }));
}

// Distance of a refined centre to the plane z = 0 along the reference ray, in
// footprints of the reference camera.
double DepthErrorFootprints(const Camera& ref, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ray = (c - ref.center()).normalized();
  return std::abs(c.z() / ray.z()) / Footprint(ref, c);
}

// Every test runs with both layouts of the device's search
// (patch_refine.cl, patch_refine_group.cl) against the one reference.
class PatchRefinerTest : public ClTest, public ::testing::WithParamInterface<RefineLayout> {
 protected:
  static PatchRefinerOptions Options() {
    PatchRefinerOptions o;
    o.layout = GetParam();
    return o;
  }

  // Refines on the device with `options` and compares with the reference;
  // `refined`, if given, receives the device's patches.
  RefComparison RefineAndCompare(const PlaneScene& scene, const std::vector<NccPatch>& patches,
                                 const std::vector<std::vector<int>>& views,
                                 const PatchRefinerOptions& options,
                                 std::vector<RefinedPatch>* refined = nullptr) {
    PatchRefiner refiner(context(), options);
    refiner.SetGroup(scene.group);
    std::vector<RefinedPatch> got = refiner.Refine(patches, views);
    const RefComparison c =
        CompareWithReference(got, PatchRefineReference(scene.group, patches, views, options));
    if (refined != nullptr) *refined = std::move(got);
    return c;
  }
};

TEST_P(PatchRefinerTest, ConvergesToThePlaneAndMatchesReference) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 51);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 12, 2.5, 15.0, 52, &patches, &views);
  // 11x11: with 7x7 on this scene (baselines of about 6 m at 40 m) the mean
  // NCC is nearly flat in the normal; the search then ends above the true
  // plane's own score (0.996 to 0.999, limited by bilinear interpolation) but
  // up to 5.2 degrees off its normal. 11x11 pins the normal to 2.4 degrees.
  PatchRefinerOptions options = Options();
  options.patch_size = 11;
  std::vector<RefinedPatch> refined;
  const RefComparison vs = RefineAndCompare(scene, patches, views, options, &refined);
  ASSERT_EQ(refined.size(), patches.size());
  const Camera& ref = scene.cameras[0];
  double worst_depth = 0.0;
  double worst_angle = 0.0;
  double lowest_score = 1.0;
  for (size_t i = 0; i < refined.size(); ++i) {
    const Eigen::Vector3d c = Xyz(refined[i].patch.center);
    const Eigen::Vector3d n(refined[i].patch.normal.s[0], refined[i].patch.normal.s[1],
                            refined[i].patch.normal.s[2]);
    const double depth_error = DepthErrorFootprints(ref, c);
    const double angle_error = AngleDeg(n, Eigen::Vector3d::UnitZ());
    EXPECT_LT(depth_error, 0.5) << "patch " << i;
    EXPECT_LT(angle_error, 5.0) << "patch " << i;
    EXPECT_GT(refined[i].score, 0.9) << "patch " << i;
    EXPECT_NEAR(n.norm(), 1.0, 1e-5);
    ASSERT_EQ(refined[i].view_scores.size(), 3u);
    double mean = 0.0;
    for (float s : refined[i].view_scores) mean += s;
    EXPECT_NEAR(mean / 3.0, refined[i].score, 1e-5);
    worst_depth = std::max(worst_depth, depth_error);
    worst_angle = std::max(worst_angle, angle_error);
    lowest_score = std::min(lowest_score, static_cast<double>(refined[i].score));
  }
  std::printf(
      "[ REFINE   ] %zu patches: worst depth error %.3f footprints, worst normal error %.2f deg, "
      "lowest score %.4f; vs reference: worst score error %.3g, %d same-path (worst depth %.3g "
      "fp, angle %.3g rad)\n",
      refined.size(), worst_depth, worst_angle, lowest_score, vs.worst_score_error, vs.same_path,
      vs.worst_depth_error, vs.worst_angle_error);
}

TEST_P(PatchRefinerTest, MatchesReferenceOnHarderStarts) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 61);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 16, 4.0, 25.0, 62, &patches, &views);
  PatchRefinerOptions options = Options();
  options.patch_size = 5;
  options.iterations = 12;
  const RefComparison c = RefineAndCompare(scene, patches, views, options);
  std::printf("[ REFINE   ] harder: worst score error %.3g, %d/%zu same-path\n",
              c.worst_score_error, c.same_path, patches.size());
  // Few iterations: the steps stay large, so the decision margins do too and
  // most searches must take the reference's exact path.
  options.iterations = 4;
  const RefComparison s = RefineAndCompare(scene, patches, views, options);
  std::printf(
      "[ REFINE   ] 4 iterations: worst score error %.3g, %d/%zu same-path (worst depth %.3g "
      "fp, angle %.3g rad)\n",
      s.worst_score_error, s.same_path, patches.size(), s.worst_depth_error, s.worst_angle_error);
  EXPECT_GE(s.same_path, static_cast<int>(patches.size()) / 2);
  // Zero iterations return the start, scored.
  options.iterations = 0;
  PatchRefiner still(context(), options);
  still.SetGroup(scene.group);
  const std::vector<RefinedPatch> start = still.Refine(patches, views);
  for (size_t i = 0; i < start.size(); ++i) {
    EXPECT_EQ(start[i].moves, 0);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(start[i].patch.center.s[k], patches[i].center.s[k], 1e-4);
      EXPECT_NEAR(start[i].patch.normal.s[k], patches[i].normal.s[k], 1e-5);
    }
  }
}

// The search stops once its steps were halved max_halvings times: with one
// halving allowed a search ends at its first failed round, so it takes at
// most as many moves as with the default, and kernel and reference stop at
// the same round. With the default, the patches still reach the plane.
TEST_P(PatchRefinerTest, StopsAfterMaxHalvings) {
  // The scene of ConvergesToThePlaneAndMatchesReference.
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 51);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 12, 2.5, 15.0, 52, &patches, &views);
  PatchRefinerOptions options = Options();
  options.patch_size = 11;
  options.iterations = 200;
  options.max_halvings = 1;
  std::vector<RefinedPatch> once;
  // Checks moves and parameters against the reference where its decisions
  // are clear.
  RefineAndCompare(scene, patches, views, options, &once);
  options.max_halvings = kDefaultRefineHalvings;
  std::vector<RefinedPatch> converged;
  RefineAndCompare(scene, patches, views, options, &converged);
  int fewer = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    // A search without a halving limit would run all 200 rounds; a stopped
    // one ran moves + 1 rounds, and moves never reach 200 here.
    EXPECT_LT(once[i].moves, options.iterations);
    EXPECT_LE(once[i].moves, converged[i].moves);
    fewer += once[i].moves < converged[i].moves;
    const Eigen::Vector3d center = Xyz(converged[i].patch.center);
    EXPECT_LT(DepthErrorFootprints(scene.cameras[0], center), 0.5) << "patch " << i;
  }
  // Stopping at the first failed round must cut some searches short.
  EXPECT_GT(fewer, 0);
}

// A patch with directions = 2 searches its depth alone: its normal comes back
// as it went in (to float precision), and on the true normal the depth still reaches
// the plane, for fewer scores than the full search of the same starts.
TEST_P(PatchRefinerTest, DepthOnlyKeepsTheNormalAndFindsTheDepth) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 51);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 12, 1.5, 0.0, 53, &patches, &views);
  PatchRefinerOptions options = Options();
  options.patch_size = 11;
  std::vector<RefinedPatch> full;
  RefineAndCompare(scene, patches, views, options, &full);
  for (NccPatch& p : patches) p.directions = 2;
  std::vector<RefinedPatch> depth_only;
  const RefComparison vs = RefineAndCompare(scene, patches, views, options, &depth_only);
  ASSERT_EQ(depth_only.size(), patches.size());
  long full_scores = 0, depth_scores = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(depth_only[i].patch.normal.s[k], patches[i].normal.s[k], 1e-6) << "patch " << i;
    }
    const Eigen::Vector3d c = Xyz(depth_only[i].patch.center);
    EXPECT_LT(DepthErrorFootprints(scene.cameras[0], c), 0.25) << "patch " << i;
    full_scores += full[i].evaluations;
    depth_scores += depth_only[i].evaluations;
  }
  EXPECT_LT(depth_scores, full_scores);
  std::printf("[ REFINE   ] depth only: %ld scores against %ld, %d/%zu same-path\n", depth_scores,
              full_scores, vs.same_path, patches.size());
}

// Sample weights (sigma_color 3, the matcher's default): the weighted search
// takes the reference's path where its decisions are clear, and converges to
// the plane as the plain one does (ConvergesToThePlaneAndMatchesReference).
TEST_P(PatchRefinerTest, WeightedNccMatchesReferenceAndConverges) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 51);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 12, 2.5, 15.0, 52, &patches, &views);
  PatchRefinerOptions options = Options();
  options.patch_size = 11;
  options.sigma_color = 3.0;
  options.iterations = 4;
  const RefComparison s = RefineAndCompare(scene, patches, views, options);
  options.iterations = kDefaultRefineIterations;
  std::vector<RefinedPatch> refined;
  const RefComparison c = RefineAndCompare(scene, patches, views, options, &refined);
  std::printf(
      "[ REFINE   ] weighted: 4 iterations %d/%zu same-path; %d iterations worst score error "
      "%.3g\n",
      s.same_path, patches.size(), options.iterations, c.worst_score_error);
  EXPECT_GE(s.same_path, static_cast<int>(patches.size()) / 2);
  const Camera& ref = scene.cameras[0];
  for (size_t i = 0; i < refined.size(); ++i) {
    const RefinedPatch& r = refined[i];
    const Eigen::Vector3d center = Xyz(r.patch.center);
    const double depth_error = DepthErrorFootprints(ref, center);
    std::printf("[ REFINE   ] weighted patch %zu: depth error %.3f footprints, score %.4f\n", i,
                depth_error, r.score);
    EXPECT_LT(depth_error, 0.5) << "patch " << i;
    EXPECT_GT(r.score, 0.9) << "patch " << i;
  }
  options.sigma_color = -1.0;
  EXPECT_FALSE(options.Check());
}

// The search stays inside the cone of max_angle_deg around the reference
// ray, as PMVS2's does: patches start facing the reference, and the plane's
// true normal lies farther off the ray than the cone allows, so each search
// ends on the cone's rim (within a step of it), never past it. A search that
// could leave the cone, or one that bounded yaw and pitch each, ended outside
// it on Herz-Jesu-P8's forecourt and the matcher rejected the patch.
TEST_P(PatchRefinerTest, StaysWithinMaxAngleOfTheReferenceRay) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 51);
  const Camera& ref = scene.cameras[0];
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  double least_true_angle = 90.0;
  for (const test::PlaneStart& s : test::PerturbedStarts(scene, 16, 0.5, 0.0, {40.0, 30.0}, 81)) {
    const Eigen::Vector3d to_ref = (ref.center() - s.center).normalized();
    least_true_angle = std::min(least_true_angle, AngleDeg(Eigen::Vector3d::UnitZ(), to_ref));
    patches.push_back(MakeNccPatch(s.center, to_ref, 0));
    views.push_back({1, 2, 3});
  }
  PatchRefinerOptions options = Options();
  options.patch_size = 11;
  options.angle_step_deg = 2.0;
  options.max_angle_deg = 0.5 * least_true_angle;
  ASSERT_GT(options.max_angle_deg, 1.0) << "the scene's camera must look obliquely enough";
  std::vector<RefinedPatch> refined;
  const RefComparison c = RefineAndCompare(scene, patches, views, options, &refined);
  int on_rim = 0, scored = 0;
  double widest = 0.0;
  for (size_t i = 0; i < refined.size(); ++i) {
    const RefinedPatch& r = refined[i];
    // A window without texture in some view scores NaN wherever it turns.
    if (!std::isfinite(r.score)) continue;
    ++scored;
    const Eigen::Vector3d center = Xyz(r.patch.center);
    const Eigen::Vector3d normal(r.patch.normal.s[0], r.patch.normal.s[1], r.patch.normal.s[2]);
    const double angle = AngleDeg(normal, ref.center() - center);
    widest = std::max(widest, angle);
    EXPECT_LE(angle, options.max_angle_deg + 1e-3) << "patch " << i;
    on_rim += angle > options.max_angle_deg - 0.5;
  }
  std::printf(
      "[ REFINE   ] cone %.2f deg (true normal >= %.2f deg off): widest %.3f deg, %d/%zu "
      "on the rim, worst score error vs reference %.3g\n",
      options.max_angle_deg, least_true_angle, widest, on_rim, refined.size(), c.worst_score_error);
  EXPECT_GE(scored, static_cast<int>(refined.size()) * 3 / 4);
  // The true normal lies outside the cone: the searches lean to the rim.
  EXPECT_GE(on_rim, scored / 2);
}

TEST_P(PatchRefinerTest, RejectsInvalidInputsBeforeEnqueue) {
  const PlaneScene scene = MakePlaneScene(4, 97, 81, 71);
  PatchRefiner refiner(context(), Options());
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 2, 1.0, 5.0, 72, &patches, &views);
  EXPECT_THROW(refiner.Refine(patches, views), Error);  // Before SetGroup.
  refiner.SetGroup(scene.group);
  EXPECT_NO_THROW(refiner.Refine(patches, views));
  auto expect_bad = [&](auto mutate, const std::string& text) {
    std::vector<NccPatch> p = patches;
    std::vector<std::vector<int>> v = views;
    mutate(p, v);
    try {
      refiner.Refine(p, v);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  using P = std::vector<NccPatch>;
  using V = std::vector<std::vector<int>>;
  expect_bad([](P&, V& v) { v.pop_back(); }, "view lists");
  expect_bad([](P&, V& v) { v[1].clear(); }, "has 0 views");
  expect_bad([](P&, V& v) { v[1].assign(kMaxViews + 1, 1); }, "views, expected 1 to");
  expect_bad([](P&, V& v) { v[0][1] = 4; }, "is not in the group");
  expect_bad([](P&, V& v) { v[0][1] = -1; }, "is not in the group");
  expect_bad([](P&, V& v) { v[0][0] = 0; }, "is its reference image");
  expect_bad([](P&, V& v) { v[1] = {1, 2, 1}; }, "is listed twice");
  expect_bad([](P& p, V&) { p[0].reference = 7; }, "reference image 7");
  expect_bad([](P& p, V&) { p[1].normal.s[2] = -p[1].normal.s[2]; }, "does not face");
  expect_bad([](P& p, V&) { p[1].normal.s[2] *= 1.5f; }, "normal has length");
  expect_bad([](P& p, V&) { p[0].center.s[0] = std::nanf(""); }, "non-finite");
  EXPECT_THROW(PatchRefiner(context(),
                            [] {
                              PatchRefinerOptions o;
                              o.iterations = -1;
                              return o;
                            }()),
               Error);
}

// Every window size the matcher refines at (7 x 7 to 21 x 21, and 3 and 9):
// the work-group layout holds 1 to 7 samples a work-item, with idle ones at
// 3 x 3 and 7 x 7, and both layouts must agree with the reference.
TEST_P(PatchRefinerTest, MatchesReferenceAtEveryWindowSize) {
  const PlaneScene scene = MakePlaneScene(4, 161, 123, 81);
  std::vector<NccPatch> patches;
  std::vector<std::vector<int>> views;
  PerturbedPatches(scene, 9, 1.5, 10.0, 82, &patches, &views);
  for (const int size : {3, 7, 9, 15, 21}) {
    PatchRefinerOptions options = Options();
    options.patch_size = size;
    options.iterations = 4;
    const RefComparison c = RefineAndCompare(scene, patches, views, options);
    std::printf("[ REFINE   ] %d x %d: worst score error %.3g, %d/%zu same-path\n", size, size,
                c.worst_score_error, c.same_path, patches.size());
    // Some searches had clear decisions all the way: their paths were compared.
    EXPECT_GE(c.same_path, 1) << size << " x " << size;
  }
}

// kAuto: a work-item per patch on a CPU device, a work-group elsewhere.
TEST_P(PatchRefinerTest, AutoLayoutIsAWorkItemOnCpusAndAWorkGroupElsewhere) {
  const PatchRefiner given(context(), Options());
  EXPECT_EQ(given.layout(), GetParam());
  const PatchRefiner automatic(context(), PatchRefinerOptions());
  EXPECT_EQ(automatic.layout(), context().device().type == DeviceType::kCpu
                                    ? RefineLayout::kPatchPerItem
                                    : RefineLayout::kPatchPerGroup);
}

INSTANTIATE_TEST_SUITE_P(Layouts, PatchRefinerTest,
                         ::testing::Values(RefineLayout::kPatchPerItem,
                                           RefineLayout::kPatchPerGroup),
                         [](const ::testing::TestParamInfo<RefineLayout>& param_info) {
                           return param_info.param == RefineLayout::kPatchPerItem ? "WorkItem"
                                                                                  : "WorkGroup";
                         });

}  // namespace
}  // namespace sapmvs

#include "device/ncc_scorer.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "device/cl_error.h"
#include "match/ncc_score_reference.h"
#include "plane_scene.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {
namespace {

// Bad options, groups, patches and pairs are refused with the index and
// value at fault before anything reaches the driver.
class NccScorerInputTest : public test::ClTest {};

TEST_F(NccScorerInputTest, RejectsBadInputBeforeEnqueue) {
  for (int size : {1, 2, 4, kMaxPatchSize + 2}) {
    NccScorerOptions options;
    options.patch_size = size;
    EXPECT_FALSE(options.Check()) << size;
    EXPECT_THROW(NccScorer(context(), options), Error) << size;
  }
  NccScorerOptions options;
  EXPECT_TRUE(options.Check());
  options.work_group_size = 0;
  EXPECT_FALSE(options.Check());
  EXPECT_THROW(NccScorer(context(), options), Error);
  for (double sigma : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    NccScorerOptions weights;
    weights.sigma_color = sigma;
    EXPECT_FALSE(weights.Check()) << sigma;
    EXPECT_THROW(
        NccScoreReference(test::MakePlaneScene(2, 31, 21, 81).group, {}, {}, 7, nullptr, sigma),
        Error)
        << sigma;
  }

  test::PlaneScene scene = test::MakePlaneScene(2, 31, 21, 81);
  NccScorer scorer(context());
  const Eigen::Vector3d ground = test::GroundAt(scene.cameras[0], Eigen::Vector2d(15, 10));
  const std::vector<NccPatch> good = {MakeNccPatch(ground, Eigen::Vector3d::UnitZ(), 0)};
  EXPECT_THROW(scorer.Score(good, {{0, 1}}), Error);  // No group yet.

  const auto expect_error = [&](const auto& call, const std::string& text) {
    try {
      call();
      ADD_FAILURE() << "expected Error containing " << text;
    } catch (const ClError& e) {
      ADD_FAILURE() << "the driver saw the bad input: " << e.what();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  NccGroup bad = scene.group;
  bad.cameras.pop_back();
  expect_error([&] { scorer.SetGroup(bad); }, "2 images but 1 cameras");
  bad = scene.group;
  bad.images[1].data = nullptr;
  expect_error([&] { scorer.SetGroup(bad); }, "image 1 has no pixel data");
  bad = scene.group;
  bad.cameras[1].p[0].s[3] = std::numeric_limits<float>::quiet_NaN();
  expect_error([&] { scorer.SetGroup(bad); }, "image 1: camera has a non-finite entry");
  bad = scene.group;
  bad.cameras[0].center.s[3] = 0.0f;
  expect_error([&] { scorer.SetGroup(bad); }, "focal length");
  expect_error([&] { scorer.SetGroup(NccGroup()); }, "no images");

  scorer.SetGroup(scene.group);
  EXPECT_EQ(scorer.Score(good, {}).size(), 0u);
  expect_error([&] { scorer.Score(good, {{1, 1}}); }, "pair 0: patch 1");
  expect_error([&] { scorer.Score(good, {{0, 0}, {0, 2}}); }, "pair 1: view 2");
  expect_error([&] { scorer.Score(good, {{0, -1}}); }, "view -1");
  std::vector<NccPatch> patches = good;
  patches[0].reference = 5;
  expect_error([&] { scorer.Score(patches, {{0, 1}}); }, "patch 0: reference image 5");
  patches = good;
  patches[0].center.s[1] = std::numeric_limits<float>::infinity();
  expect_error([&] { scorer.Score(patches, {{0, 1}}); }, "non-finite");
  patches = good;
  patches[0].normal.s[2] = 0.9f;
  expect_error([&] { scorer.Score(patches, {{0, 1}}); }, "normal has length");
  expect_error([&] { scorer.ProbeSamples(2, {{0, 0}}); }, "probe image 2");

  // The reference applies the same checks.
  EXPECT_THROW(NccScoreReference(scene.group, good, {{0, 3}}, 7), Error);
  EXPECT_THROW(NccScoreReference(scene.group, good, {{0, 1}}, 6), Error);

  Camera distorted = scene.cameras[0];
  Intrinsics intrinsics = distorted.intrinsics();
  intrinsics.distortion.k1 = 0.1;
  EXPECT_THROW(MakeNccCamera(distorted.WithIntrinsics(intrinsics)), Error);
}

}  // namespace
}  // namespace sapmvs

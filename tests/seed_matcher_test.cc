#include "match/seed_matcher.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "match/group_data.h"
#include "plane_scene.h"
#include "sapmvs/block/camera.h"
#include "sapmvs/match/matcher_options.h"

namespace sapmvs {
namespace {

// A camera about `height` above `target` looking roughly down at it.
Camera LookingDown(std::mt19937& rng, const Eigen::Vector3d& offset, double height) {
  std::uniform_real_distribution<double> tilt(-15, 15), kappa(-180, 180), pos(-60, 60);
  const Intrinsics k = Intrinsics::FromPixels(1000, 1003, 639.5 + 3.0, 479.5 - 2.0, 1280, 960);
  return Camera::FromAngles(k, offset + Eigen::Vector3d(pos(rng), pos(rng), height), tilt(rng),
                            tilt(rng), kappa(rng), AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
}

// Recovers points seen in two random cameras, exactly up to rounding:
// relative to the distance from camera a.
void ExpectRecoversProjectedPoints(const Eigen::Vector3d& offset, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ground(-40, 40), relief(-10, 10);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Camera a = LookingDown(rng, offset, 200);
    const Camera b = LookingDown(rng, offset, 210);
    const Eigen::Vector3d x = offset + Eigen::Vector3d(ground(rng), ground(rng), relief(rng));
    const Eigen::Vector2d uv_a = a.Project(x), uv_b = b.Project(x);
    if (!uv_a.allFinite() || !uv_b.allFinite()) continue;
    // Nearly parallel rays would measure the conditioning, not the method.
    if ((a.center() - b.center()).norm() < 20) continue;
    ++tested;
    const Eigen::Vector3d got = TriangulateMidpoint(a, uv_a, b, uv_b);
    ASSERT_TRUE(got.allFinite()) << "trial " << trial;
    EXPECT_LE((got - x).norm(), 1e-9 * (x - a.center()).norm())
        << "trial " << trial << ": got (" << got.transpose() << "), expected (" << x.transpose()
        << ")";
  }
  EXPECT_GT(tested, 100);
}

TEST(TriangulateMidpoint, RecoversAKnownPointLocalFrame) {
  ExpectRecoversProjectedPoints(Eigen::Vector3d::Zero(), 11);
}

TEST(TriangulateMidpoint, RecoversAKnownPointUtmCoordinates) {
  ExpectRecoversProjectedPoints(Eigen::Vector3d(512345.0, 5405678.0, 300.0), 12);
}

TEST(TriangulateMidpoint, SkewRaysGiveTheMidpointOfTheCommonPerpendicular) {
  // Through their principal points, camera a's ray is the z axis and camera
  // b's the line y = 2, z = 4 along +x: they miss each other by 2, closest at
  // (0, 0, 4) and (0, 2, 4).
  const Intrinsics k = Intrinsics::FromPixels(500, 500, 200, 150, 401, 301);
  const Camera a(k, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  Eigen::Matrix3d r_wc;  // rows: the camera's x, y, z axes in the world
  r_wc.row(0) = Eigen::Vector3d(0, 0, -1);
  r_wc.row(1) = Eigen::Vector3d(0, 1, 0);
  r_wc.row(2) = Eigen::Vector3d(1, 0, 0);
  const Camera b(k, r_wc, Eigen::Vector3d(-10, 2, 4));
  const Eigen::Vector3d got =
      TriangulateMidpoint(a, Eigen::Vector2d(200, 150), b, Eigen::Vector2d(200, 150));
  EXPECT_LE((got - Eigen::Vector3d(0, 1, 4)).norm(), 1e-12) << got.transpose();
}

TEST(TriangulateMidpoint, IdenticalRaysAreNotFinite) {
  std::mt19937 rng(13);
  const Camera a = LookingDown(rng, Eigen::Vector3d::Zero(), 200);
  const Eigen::Vector3d got =
      TriangulateMidpoint(a, Eigen::Vector2d(300, 200), a, Eigen::Vector2d(300, 200));
  EXPECT_FALSE(got.allFinite()) << got.transpose();
}

TEST(TriangulateMidpoint, ParallelRaysFromTwoCentresAreNotFinite) {
  // Same orientation, camera b moved sideways: the same pixel's rays are
  // parallel and never meet.
  std::mt19937 rng(14);
  const Camera a = LookingDown(rng, Eigen::Vector3d::Zero(), 200);
  const Camera b(a.intrinsics(), a.rotation(), a.center() + Eigen::Vector3d(30, -5, 2));
  for (const Eigen::Vector2d& uv : {Eigen::Vector2d(639.5, 479.5), Eigen::Vector2d(10, 900)}) {
    const Eigen::Vector3d got = TriangulateMidpoint(a, uv, b, uv);
    EXPECT_FALSE(got.allFinite()) << "uv (" << uv.transpose() << "): " << got.transpose();
  }
}

// The candidates of feature f of image 0 in image 1 by their definition, over
// every feature of image 1: the same kind, within epipolar_distance of the
// segment between the seed depths, and triangulated within those depths.
std::vector<Eigen::Vector3d> BruteForceCandidates(const MatchGroupData& group, const Feature& f,
                                                  const std::vector<Feature>& others,
                                                  double epipolar_distance) {
  const MatchImage& ref = group.images[0];
  const Camera& cam = group.images[1].camera;
  const Eigen::Vector3d near_point = ref.camera.BackProject(f.uv, kSeedDepthMin * ref.depth);
  const Eigen::Vector3d far_point = ref.camera.BackProject(f.uv, kSeedDepthMax * ref.depth);
  const Eigen::Vector2d a = cam.Project(near_point), b = cam.Project(far_point);
  std::vector<Eigen::Vector3d> out;
  for (const Feature& g : others) {
    if (g.kind != f.kind) continue;
    const double t = (g.uv - a).dot(b - a) / (b - a).squaredNorm();
    if (t < 0 || t > 1 || (g.uv - (a + t * (b - a))).norm() > epipolar_distance) continue;
    const Eigen::Vector3d x = TriangulateMidpoint(ref.camera, f.uv, cam, g.uv);
    const double depth = ref.camera.Depth(x);
    if (!x.allFinite() || depth < kSeedDepthMin * ref.depth || depth > kSeedDepthMax * ref.depth) {
      continue;
    }
    out.push_back(x);
  }
  return out;
}

// Two images of a plane scene (241 x 181), each the other's view.
MatchGroupData TwoImageGroup() {
  const test::PlaneScene scene = test::MakePlaneScene(2, 241, 181, 17);
  MatchGroupData group;
  for (int i = 0; i < 2; ++i) {
    MatchImage image;
    image.camera = scene.cameras[i];
    image.views = {1 - i};
    image.depth = image.camera.Depth(test::GroundAt(image.camera, Eigen::Vector2d(120, 90)));
    group.images.push_back(image);
  }
  return group;
}

// n features at random over a 241 x 181 image, Harris and DoG in turn.
void AddRandomFeatures(std::mt19937& rng, int n, std::vector<Feature>* out) {
  std::uniform_real_distribution<double> x(0.0, 240.0), y(0.0, 180.0);
  for (int k = 0; k < n; ++k) {
    Feature f;
    f.uv = Eigen::Vector2d(x(rng), y(rng));
    f.kind = k % 2 == 0 ? FeatureKind::kHarris : FeatureKind::kDog;
    out->push_back(f);
  }
}

// A candidates_per_feature above any feature's partner count: every candidate
// is kept.
constexpr int kKeepEvery = 100000;

// Seed matching searches only the features near each epipolar segment (a
// bucket walk along it, clipped to the image): it must find exactly the
// candidates a scan of every feature finds, including features just inside
// and just outside epipolar_distance, features of the other kind on the
// line, and segments that leave the image.
TEST(SeedMatcherTest, FindsExactlyTheCandidatesOfAFullScan) {
  MatchGroupData group = TwoImageGroup();
  MatcherOptions options;
  options.candidates_per_feature = kKeepEvery;
  std::mt19937 rng(5);
  std::vector<std::vector<Feature>> features(2);
  // Image 0: features all over it, near its borders too.
  AddRandomFeatures(rng, 60, &features[0]);
  // Image 1: random features, plus for each feature of image 0 its match on
  // the ground and features 1.9 and 2.1 px across its epipolar line, and one
  // of the other kind on the line; all inside the image, as detected ones are.
  AddRandomFeatures(rng, 1500, &features[1]);
  const Camera& c0 = group.images[0].camera;
  const Camera& c1 = group.images[1].camera;
  for (const Feature& f : features[0]) {
    const Eigen::Vector2d on = c1.Project(test::GroundAt(c0, f.uv));
    const Eigen::Vector2d along =
        (c1.Project(c0.BackProject(f.uv, kSeedDepthMax * group.images[0].depth)) -
         c1.Project(c0.BackProject(f.uv, kSeedDepthMin * group.images[0].depth)))
            .normalized();
    const Eigen::Vector2d across(-along.y(), along.x());
    auto inside = [](const Eigen::Vector2d& uv) {
      return uv.x() >= 0 && uv.y() >= 0 && uv.x() <= 240 && uv.y() <= 180;
    };
    for (const double offset : {0.0, 1.9, -1.9, 2.1, -2.1}) {
      Feature g;
      g.uv = on + offset * across;
      g.kind = f.kind;
      if (inside(g.uv)) features[1].push_back(g);
    }
    Feature other;
    other.uv = on;
    other.kind = f.kind == FeatureKind::kHarris ? FeatureKind::kDog : FeatureKind::kHarris;
    if (inside(other.uv)) features[1].push_back(other);
  }

  const std::vector<SeedFeature> seeds = MatchSeeds(group, features, options);
  long compared = 0, candidates = 0;
  for (const Feature& f : features[0]) {
    std::vector<Eigen::Vector3d> want =
        BruteForceCandidates(group, f, features[1], options.epipolar_distance);
    const auto found = std::find_if(seeds.begin(), seeds.end(), [&](const SeedFeature& s) {
      return s.image == 0 && s.uv == f.uv;
    });
    std::vector<Eigen::Vector3d> got;
    if (found != seeds.end()) {
      for (const PatchCandidate& c : found->candidates) got.push_back(c.center);
    }
    ASSERT_EQ(got.size(), want.size()) << "feature at " << f.uv.transpose();
    auto less = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      return std::lexicographical_compare(p.data(), p.data() + 3, q.data(), q.data() + 3);
    };
    std::sort(got.begin(), got.end(), less);
    std::sort(want.begin(), want.end(), less);
    for (size_t k = 0; k < got.size(); ++k) {
      EXPECT_LT((got[k] - want[k]).norm(), 1e-9) << "feature at " << f.uv.transpose();
    }
    ++compared;
    candidates += static_cast<long>(want.size());
  }
  EXPECT_EQ(compared, static_cast<long>(features[0].size()));
  // Each feature has at least its ground match and the two within 1.9 px,
  // where its segment stays over image 1.
  EXPECT_GT(candidates, 2 * static_cast<long>(features[0].size()));
}

// Seeds for some reference features only (the later features of each block,
// matched once the first waves have run): exactly those features' seeds of
// a call for all, since every feature of the views stays a partner, their
// support included.
TEST(SeedMatcherTest, WantedFeaturesGetTheSeedsOfACallForAll) {
  const test::PlaneScene scene = test::MakePlaneScene(3, 241, 181, 23);
  MatchGroupData group;
  for (int i = 0; i < 3; ++i) {
    MatchImage image;
    image.camera = scene.cameras[i];
    for (int j = 0; j < 3; ++j) {
      if (j != i) image.views.push_back(j);
    }
    image.depth = image.camera.Depth(test::GroundAt(image.camera, Eigen::Vector2d(120, 90)));
    group.images.push_back(image);
  }
  MatcherOptions options;
  std::mt19937 rng(23);
  std::vector<std::vector<Feature>> features(3);
  for (auto& f : features) AddRandomFeatures(rng, 300, &f);
  // Each feature's match in the other images, so that seeds have partners
  // and support.
  for (size_t k = 0; k < 300; ++k) {
    const Eigen::Vector3d ground = test::GroundAt(group.images[0].camera, features[0][k].uv);
    for (int j = 1; j < 3; ++j) {
      Feature g = features[0][k];
      g.uv = group.images[j].camera.Project(ground);
      features[j].push_back(g);
    }
  }
  for (auto& image : features) {
    for (size_t k = 0; k < image.size(); ++k) image[k].block_rank = static_cast<int>(k % 3);
  }
  auto wanted = [](int image, const Feature& f) { return image != 1 && f.block_rank == 2; };
  const std::vector<SeedFeature> all = MatchSeeds(group, features, options);
  const std::vector<SeedFeature> some = MatchSeeds(group, features, options, wanted);
  std::vector<const SeedFeature*> expected;
  for (const SeedFeature& s : all) {
    const auto f = std::find_if(features[s.image].begin(), features[s.image].end(),
                                [&](const Feature& g) { return g.uv == s.uv; });
    ASSERT_NE(f, features[s.image].end());
    if (wanted(s.image, *f)) expected.push_back(&s);
  }
  ASSERT_GT(expected.size(), 50u);
  ASSERT_LT(expected.size(), all.size() / 2);
  ASSERT_EQ(some.size(), expected.size());
  for (size_t i = 0; i < some.size(); ++i) {
    EXPECT_EQ(some[i].image, expected[i]->image);
    EXPECT_EQ(some[i].uv, expected[i]->uv);
    ASSERT_EQ(some[i].candidates.size(), expected[i]->candidates.size()) << "seed " << i;
    for (size_t c = 0; c < some[i].candidates.size(); ++c) {
      EXPECT_EQ(some[i].candidates[c].center, expected[i]->candidates[c].center)
          << "seed " << i << ", candidate " << c;
    }
  }
}

// The candidates are ranked by support (the other views with a feature of
// the same kind within epipolar_distance of the candidate's projection),
// then by distance from the epipolar line, then in the order the partners
// were found (view, then feature). The support test reads a per-pixel mask
// before the exact distances, and when only the best `keep` are asked for,
// stops counting a partner's support once it cannot enter them: the
// ranking must be the definition's first `keep`, with supports just inside
// and just outside the distance, and of the other kind, in the other views.
// Returns how many epipolar segments ran mostly along x and along y (the
// feature search walks them along their major axis).
std::pair<long, long> ExpectRankingAsDefined(int num_images, int keep, uint32_t seed) {
  const test::PlaneScene scene = test::MakePlaneScene(num_images, 241, 181, seed);
  MatchGroupData group;
  for (int i = 0; i < num_images; ++i) {
    MatchImage image;
    image.camera = scene.cameras[i];
    for (int j = 0; j < num_images; ++j) {
      if (j != i) image.views.push_back(j);
    }
    image.depth = image.camera.Depth(test::GroundAt(image.camera, Eigen::Vector2d(120, 90)));
    group.images.push_back(image);
  }
  MatcherOptions options;
  options.candidates_per_feature = keep;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI);
  std::vector<std::vector<Feature>> features(num_images);
  AddRandomFeatures(rng, 40, &features[0]);
  for (int j = 1; j < num_images; ++j) AddRandomFeatures(rng, 400, &features[j]);
  auto inside = [](const Eigen::Vector2d& uv) {
    return uv.x() >= 0 && uv.y() >= 0 && uv.x() <= 240 && uv.y() <= 180;
  };
  for (size_t k = 0; k < features[0].size(); ++k) {
    const Feature& f = features[0][k];
    const Eigen::Vector3d ground = test::GroundAt(group.images[0].camera, f.uv);
    for (int j = 1; j < num_images; ++j) {
      // Its match, and around the match a feature 1.9, 2.0 or 2.1 px away in
      // a random direction, of its kind or of the other.
      Feature g = f;
      g.uv = group.images[j].camera.Project(ground);
      if (inside(g.uv)) features[j].push_back(g);
      const double a = angle(rng);
      g.uv += (1.9 + 0.1 * static_cast<double>(k % 3)) * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (k % 4 == 3)
        g.kind = f.kind == FeatureKind::kHarris ? FeatureKind::kDog : FeatureKind::kHarris;
      if (inside(g.uv)) features[j].push_back(g);
    }
  }

  const std::vector<SeedFeature> seeds = MatchSeeds(group, features, options);
  const MatchImage& ref = group.images[0];
  long compared = 0, supported = 0, supported_best = 0, along_x = 0, along_y = 0;
  for (const Feature& f : features[0]) {
    // The definition, over every feature: partners in each view, in view
    // order, then ranked.
    struct Want {
      Eigen::Vector3d x;
      int support;
      double epipolar;
    };
    std::vector<Want> want;
    for (const int j : ref.views) {
      const Camera& cam = group.images[j].camera;
      const Eigen::Vector2d a =
          cam.Project(ref.camera.BackProject(f.uv, kSeedDepthMin * ref.depth));
      const Eigen::Vector2d b =
          cam.Project(ref.camera.BackProject(f.uv, kSeedDepthMax * ref.depth));
      ++(std::abs(b.x() - a.x()) >= std::abs(b.y() - a.y()) ? along_x : along_y);
      for (const Feature& g : features[j]) {
        if (g.kind != f.kind) continue;
        const double t = (g.uv - a).dot(b - a) / (b - a).squaredNorm();
        const double dist = (g.uv - (a + t * (b - a))).norm();
        if (t < 0 || t > 1 || dist > options.epipolar_distance) continue;
        const Eigen::Vector3d p = TriangulateMidpoint(ref.camera, f.uv, cam, g.uv);
        const double depth = ref.camera.Depth(p);
        if (!p.allFinite() || depth < kSeedDepthMin * ref.depth ||
            depth > kSeedDepthMax * ref.depth) {
          continue;
        }
        int support = 0;
        for (const int k : ref.views) {
          if (k == j || !(group.images[k].camera.Depth(p) > 0)) continue;
          const Eigen::Vector2d q = group.images[k].camera.Project(p);
          support += std::any_of(features[k].begin(), features[k].end(), [&](const Feature& h) {
            return h.kind == f.kind && (h.uv - q).norm() <= options.epipolar_distance;
          });
        }
        want.push_back({p, support, dist});
      }
    }
    std::stable_sort(want.begin(), want.end(), [](const Want& p, const Want& q) {
      return p.support != q.support ? p.support > q.support : p.epipolar < q.epipolar;
    });
    if (static_cast<int>(want.size()) > keep) want.resize(keep);
    const auto found = std::find_if(seeds.begin(), seeds.end(), [&](const SeedFeature& s) {
      return s.image == 0 && s.uv == f.uv;
    });
    const size_t got = found == seeds.end() ? 0 : found->candidates.size();
    EXPECT_EQ(got, want.size()) << "feature at " << f.uv.transpose();
    for (size_t k = 0; k < std::min(got, want.size()); ++k) {
      EXPECT_LT((found->candidates[k].center - want[k].x).norm(), 1e-9)
          << "feature at " << f.uv.transpose() << ", candidate " << k;
      supported += want[k].support > 0;
    }
    supported_best += !want.empty() && want[0].support > 0;
    ++compared;
  }
  EXPECT_EQ(compared, static_cast<long>(features[0].size()));
  // Kept whole, the candidates hold more supported ones than there are
  // features; kept to a few, most features' best is supported.
  if (keep >= kKeepEvery) {
    EXPECT_GT(supported, static_cast<long>(features[0].size())) << "too few supported candidates";
  }
  EXPECT_GT(2 * supported_best, static_cast<long>(features[0].size()))
      << "too few features whose best candidate has support";
  return {along_x, along_y};
}

TEST(SeedMatcherTest, RanksCandidatesBySupportAsTheDefinitionDoes) {
  ExpectRankingAsDefined(3, kKeepEvery, 7);
}

// Five images: supports of 0 to 3, epipolar segments in several directions.
// Keeping 2 of the 10-30 partners a feature has, most counts stop early.
TEST(SeedMatcherTest, KeepsTheBestCandidatesAsTheDefinitionRanksThem) {
  long along_x = 0, along_y = 0;
  for (const int keep : {kKeepEvery, 2, 1}) {
    const auto [x, y] = ExpectRankingAsDefined(5, keep, 29);
    along_x += x;
    along_y += y;
  }
  EXPECT_GT(along_x, 0);
  EXPECT_GT(along_y, 0);
}

// A view-only image (another strip's, ImageGroup::views) lends its features
// as partners but starts no seed.
TEST(SeedMatcherTest, AViewOnlyImageStartsNoSeed) {
  MatchGroupData group = TwoImageGroup();
  // The same ground point's feature in both images.
  std::vector<std::vector<Feature>> features(2);
  for (int k = 0; k < 20; ++k) {
    Feature f;
    f.uv = Eigen::Vector2d(60 + 6 * k, 60 + 3 * k);
    features[0].push_back(f);
    Feature g = f;
    g.uv = group.images[1].camera.Project(test::GroundAt(group.images[0].camera, f.uv));
    features[1].push_back(g);
  }
  const MatcherOptions options;
  std::vector<SeedFeature> seeds = MatchSeeds(group, features, options);
  ASSERT_FALSE(seeds.empty());
  EXPECT_TRUE(
      std::any_of(seeds.begin(), seeds.end(), [](const SeedFeature& s) { return s.image == 1; }));
  group.images[1].reference = false;
  seeds = MatchSeeds(group, features, options);
  ASSERT_FALSE(seeds.empty());
  for (const SeedFeature& s : seeds) {
    EXPECT_EQ(s.image, 0);
    for (const PatchCandidate& c : s.candidates) EXPECT_EQ(c.ref, 0);
  }
}

}  // namespace
}  // namespace sapmvs

#include "match/propagation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <utility>

#include <opencv2/core.hpp>

#include "match/group_data.h"
#include "match/patch_engine.h"
#include "match/reference_patch_kernels.h"
#include "plane_scene.h"
#include "sapmvs/block/camera.h"
#include "sapmvs/util/memory_use.h"

namespace sapmvs {
namespace {

Camera TiltedCamera(std::mt19937& rng, const Eigen::Vector3d& offset) {
  std::uniform_real_distribution<double> tilt(-25, 25), kappa(-180, 180), pos(-30, 30);
  const Intrinsics k = Intrinsics::FromPixels(800, 805, 320.5, 238.0, 641, 481);
  return Camera::FromAngles(k, offset + Eigen::Vector3d(pos(rng), pos(rng), 120 + pos(rng)),
                            tilt(rng), tilt(rng), kappa(rng), AngleOrder::kOmegaPhiKappa,
                            AngleUnit::kDegree);
}

bool AllNan(const Eigen::Vector3d& x) {
  return std::isnan(x.x()) && std::isnan(x.y()) && std::isnan(x.z());
}

// A random plane through a point near the ground under the camera, tilted by
// up to 60 degrees, and a point on it in front of the camera.
void ExpectReturnsThePointOnThePlane(const Eigen::Vector3d& offset, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1, 1), along(-15, 15);
  int tested = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Camera camera = TiltedCamera(rng, offset);
    const Eigen::Vector3d c =
        offset + Eigen::Vector3d(10 * unit(rng), 10 * unit(rng), 5 * unit(rng));
    const Eigen::Vector3d n =
        (Eigen::AngleAxisd(1.05 * unit(rng),
                           Eigen::Vector3d(unit(rng), unit(rng), 0).normalized()) *
         Eigen::Vector3d::UnitZ())
            .normalized();
    // Two directions in the plane.
    const Eigen::Vector3d t1 = n.unitOrthogonal();
    const Eigen::Vector3d t2 = n.cross(t1);
    const Eigen::Vector3d x = c + along(rng) * t1 + along(rng) * t2;
    const Eigen::Vector2d uv = camera.Project(x);
    if (!uv.allFinite()) continue;
    // Grazing rays would measure the conditioning, not the method.
    if (std::abs(n.dot(camera.Ray(uv))) < 0.2) continue;
    ++tested;
    const Eigen::Vector3d got = IntersectPlane(camera, uv, c, n);
    ASSERT_TRUE(got.allFinite()) << "trial " << trial;
    EXPECT_LE((got - x).norm(), 1e-9 * (x - camera.center()).norm())
        << "trial " << trial << ": got (" << got.transpose() << "), expected (" << x.transpose()
        << ")";
    // The plane's normal may point either way.
    EXPECT_LE((IntersectPlane(camera, uv, c, -n) - x).norm(), 1e-9 * (x - camera.center()).norm());
  }
  EXPECT_GT(tested, 100);
}

TEST(IntersectPlane, ReturnsThePointWhoseProjectionTheRayPassesThrough) {
  ExpectReturnsThePointOnThePlane(Eigen::Vector3d::Zero(), 21);
}

TEST(IntersectPlane, ReturnsThePointInUtmCoordinates) {
  ExpectReturnsThePointOnThePlane(Eigen::Vector3d(512345.0, 5405678.0, 300.0), 22);
}

TEST(IntersectPlane, HorizontalGroundUnderANadirCamera) {
  // Nadir camera 100 above z = 0: the principal point sees the ground right
  // below, and pixel (cx + 80, cy) sees 10 further along +x (f = 800).
  Eigen::Matrix3d r_wc;
  r_wc.row(0) = Eigen::Vector3d(1, 0, 0);
  r_wc.row(1) = Eigen::Vector3d(0, -1, 0);
  r_wc.row(2) = Eigen::Vector3d(0, 0, -1);
  const Camera camera(Intrinsics::FromPixels(800, 800, 320, 240, 641, 481), r_wc,
                      Eigen::Vector3d(5, 7, 100));
  const Eigen::Vector3d c(-3, 4, 0), n(0, 0, 1);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(320, 240), c, n) - Eigen::Vector3d(5, 7, 0)).norm(),
      1e-12);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(400, 240), c, n) - Eigen::Vector3d(15, 7, 0)).norm(),
      1e-12);
  EXPECT_LE(
      (IntersectPlane(camera, Eigen::Vector2d(320, 160), c, n) - Eigen::Vector3d(5, 17, 0)).norm(),
      1e-12);
}

TEST(IntersectPlane, PlaneParallelToTheRayIsNan) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = TiltedCamera(rng, Eigen::Vector3d::Zero());
    const Eigen::Vector2d uv(100 + 20 * trial, 50 + 15 * trial);
    const Eigen::Vector3d ray = camera.Ray(uv);
    // A plane containing the ray's direction, off the ray and through it.
    const Eigen::Vector3d n = ray.unitOrthogonal();
    const Eigen::Vector3d off = camera.center() - 50 * n + 80 * ray;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, off, n))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, camera.center() + 80 * ray, n)))
        << "trial " << trial;
  }
}

TEST(IntersectPlane, PlaneBehindTheCameraIsNan) {
  std::mt19937 rng(24);
  for (int trial = 0; trial < 20; ++trial) {
    const Camera camera = TiltedCamera(rng, Eigen::Vector3d::Zero());
    const Eigen::Vector2d uv(100 + 20 * trial, 50 + 15 * trial);
    const Eigen::Vector3d ray = camera.Ray(uv);
    // The ray's line meets these planes 40 behind the centre.
    const Eigen::Vector3d behind = camera.center() - 40 * ray;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, ray))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, -ray))) << "trial " << trial;
    EXPECT_TRUE(AllNan(IntersectPlane(camera, uv, behind, Eigen::Vector3d::UnitZ())))
        << "trial " << trial;
    // The same plane moved in front of the camera is hit.
    const Eigen::Vector3d ahead = camera.center() + 40 * ray;
    EXPECT_LE((IntersectPlane(camera, uv, ahead, ray) - ahead).norm(), 1e-9) << "trial " << trial;
  }
}

// Textured ground: grey 94 to 108 in a fine checker.
cv::Mat Checker(int width, int height) {
  cv::Mat grey(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) grey.at<float>(y, x) = ((x + y) % 2 ? 106.0f : 94.0f) + x % 3;
  }
  return grey;
}

std::set<std::pair<int, int>> PixelSet(const std::vector<std::pair<int, int>>& v) {
  return {v.begin(), v.end()};
}

const auto kNoBarrier = [](int, int) { return false; };

TEST(WindowPixels, WithoutWeightsOrBarriersIsTheWholeWindowInsideTheImage) {
  const cv::Mat grey = Checker(40, 30);
  for (const int side : {3, 7, 11, 21}) {
    const auto all = WindowPixels(grey, 20, 15, side, 3.0, 0.0, kNoBarrier);
    EXPECT_EQ(static_cast<int>(all.size()), side * side) << side;
    EXPECT_EQ(all.front(), std::make_pair(20, 15));
    EXPECT_EQ(PixelSet(all).size(), all.size());
    EXPECT_EQ(WindowPixels(grey, 20, 15, side, 0.0, 0.3, kNoBarrier).size(), all.size());
  }
  // Clipped at the image's border: the corner's 11 x 11 window keeps 6 x 6.
  EXPECT_EQ(WindowPixels(grey, 0, 0, 11, 0.0, 0.0, kNoBarrier).size(), 36u);
  EXPECT_EQ(WindowPixels(grey, 39, 29, 11, 3.0, 0.3, kNoBarrier).size(), 36u);
  EXPECT_TRUE(WindowPixels(grey, 40, 0, 11, 3.0, 0.3, kNoBarrier).empty());
}

TEST(WindowPixels, StopsAtAStepEdge) {
  // A bright roof (x >= 23) beside textured ground: a ground window that
  // reaches over the edge writes no point on the roof, and keeps all of its
  // ground.
  cv::Mat grey = Checker(50, 40);
  grey(cv::Rect(23, 0, 27, 40)).setTo(200.0f);
  const auto got = PixelSet(WindowPixels(grey, 19, 20, 21, 3.0, 0.3, kNoBarrier));
  for (int y = 10; y <= 30; ++y) {
    for (int x = 9; x <= 29; ++x) {
      EXPECT_EQ(got.count({x, y}), x < 23 ? 1u : 0u) << x << ", " << y;
    }
  }
  // A flat centre has no texture to weigh by: the whole window.
  const auto roof = PixelSet(WindowPixels(grey, 30, 20, 7, 3.0, 0.3, kNoBarrier));
  EXPECT_EQ(roof.size(), 49u);
}

TEST(WindowPixels, AWallStripeClosesTheWindowBehindIt) {
  // A dark wall two pixels wide (x = 24, 25) across the window: the ground
  // beyond it looks like the centre's but is not connected to it.
  cv::Mat grey = Checker(50, 40);
  grey(cv::Rect(24, 0, 2, 40)).setTo(20.0f);
  const auto got = PixelSet(WindowPixels(grey, 20, 20, 15, 3.0, 0.3, kNoBarrier));
  for (const auto& [x, y] : got) EXPECT_LT(x, 24) << x << ", " << y;
  EXPECT_EQ(got.size(), 11u * 15u);  // x = 13 to 23
}

TEST(WindowPixels, KeepsToOneSideOfATreeCrown) {
  // A crown: a disk of radius 6 of a darker, textured green.
  cv::Mat grey = Checker(60, 60);
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 60; ++x) {
      if ((x - 30) * (x - 30) + (y - 30) * (y - 30) <= 36) {
        grey.at<float>(y, x) = ((x + y) % 2 ? 43.0f : 37.0f);
      }
    }
  }
  auto in_crown = [](int x, int y) { return (x - 30) * (x - 30) + (y - 30) * (y - 30) <= 36; };
  // From the ground beside it, none of the crown.
  for (const auto& [x, y] : WindowPixels(grey, 22, 30, 21, 3.0, 0.3, kNoBarrier)) {
    EXPECT_FALSE(in_crown(x, y)) << x << ", " << y;
  }
  // From the crown, none of the ground, and all of the crown in the window.
  const auto crown = WindowPixels(grey, 30, 30, 21, 3.0, 0.3, kNoBarrier);
  for (const auto& [x, y] : crown) EXPECT_TRUE(in_crown(x, y)) << x << ", " << y;
  EXPECT_EQ(crown.size(), 113u);  // the pixels of the disk of radius 6
}

TEST(WindowPixels, AMatchedEdgeLineIsABarrier) {
  // An 8-connected diagonal barrier line through the window: the far side
  // stays out although its grey levels are the centre's.
  const cv::Mat grey = Checker(40, 40);
  auto diagonal = [](int x, int y) { return x + y == 44; };
  const auto got = WindowPixels(grey, 20, 20, 21, 3.0, 0.3, diagonal);
  ASSERT_FALSE(got.empty());
  for (const auto& [x, y] : got) EXPECT_LT(x + y, 44) << x << ", " << y;
}

// The scene as a group whose grey images (for the emission) are its pixels,
// which must outlive it.
MatchGroupData GroupWithGrey(test::PlaneScene& scene) {
  MatchGroupData group = test::MatchGroupOf(scene);
  for (size_t i = 0; i < group.images.size(); ++i) {
    const Camera& camera = scene.cameras[i];
    group.images[i].grey = cv::Mat(camera.height(), camera.width(), CV_32F, scene.pixels[i].data());
  }
  return group;
}

// `count` seeds of image 0, each with one candidate near the ground.
std::vector<SeedFeature> SeedsInImage0(const test::PlaneScene& scene, int count) {
  std::vector<SeedFeature> seeds;
  for (const test::PlaneStart& s : test::PerturbedStarts(scene, count, 0.2, 2.0, {25.0, 20.0}, 5)) {
    SeedFeature f;
    f.image = 0;
    f.uv = scene.cameras[0].Project(s.center);
    PatchCandidate c;
    c.center = s.center;
    c.normal = s.normal;
    c.ref = 0;
    f.candidates.push_back(c);
    seeds.push_back(f);
  }
  return seeds;
}

// The points are reserved once, for as many as the reference cells can hold
// (one per pixel, one per cell in pmvs mode), so that the waves append to
// the array without copying it.
TEST(Propagator, ReservesItsPointsOnceForWhatTheCellsHold) {
  if (!UnwrittenMemoryIsFree()) {
    GTEST_SKIP()
        << "an address-space or data limit, or strict overcommit: the points are not reserved";
  }
  test::PlaneScene scene = test::MakePlaneScene(3, 121, 97, 17);
  const MatchGroupData group = GroupWithGrey(scene);
  const std::vector<SeedFeature> seeds = SeedsInImage0(scene, 6);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  for (const MatchMode mode : {MatchMode::kSapmvs, MatchMode::kPmvs}) {
    SCOPED_TRACE(mode == MatchMode::kPmvs ? "pmvs" : "sapmvs");
    MatcherOptions options;
    options.mode = mode;
    options.max_angle_deg = 5.0;  // the cameras are a few metres apart at 40 m
    options.max_waves = 3;
    const size_t cs = static_cast<size_t>(options.cell_size);
    size_t cells = 0;
    for (const Camera& camera : scene.cameras) {
      cells += ((camera.width() + cs - 1) / cs) * ((camera.height() + cs - 1) / cs);
    }
    PatchEngine engine(*kernels, group, options);
    Propagator propagator(group, options, engine);
    EXPECT_EQ(propagator.points().capacity(), cells * (mode == MatchMode::kPmvs ? 1 : cs * cs));
    const DensePoint* array = propagator.points().data();
    propagator.RunSeeds(seeds);
    propagator.RunWaves({});
    EXPECT_GT(propagator.points().size(), seeds.size());
    EXPECT_EQ(propagator.points().data(), array);
  }
}

// The pmvs passes' candidates are evaluated as pmvs mode's, within their own
// cone; everything else is the adaptive passes' options.
TEST(PmvsPassOptions, ScoreAsPmvsModeWithinTheirOwnCone) {
  MatcherOptions options;
  options.pmvs_pass_view_angle_deg = 75;
  options.threshold = 0.8;
  const MatcherOptions pmvs = PmvsPassOptions(options);
  EXPECT_EQ(pmvs.mode, MatchMode::kPmvs);
  EXPECT_EQ(pmvs.view_angle_deg, 75);
  EXPECT_EQ(pmvs.threshold, 0.8);
  EXPECT_EQ(pmvs.window_size, options.window_size);
  EXPECT_EQ(options.view_angle_deg, 60);
}

// After GrowAsPmvs, Prune queues every point's rim and the waves grow as in
// pmvs mode: from the adaptive patches' points into the cells beside them,
// one-cell patches of window_size that emit their centres only; their
// points lie on the true plane as the adaptive patches' do.
TEST(Propagator, GrowsAsPmvsFromTheRimsOfTheAdaptivePatches) {
  test::PlaneScene scene = test::MakePlaneScene(3, 121, 97, 17);
  const MatchGroupData group = GroupWithGrey(scene);
  const std::vector<SeedFeature> seeds = SeedsInImage0(scene, 4);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  MatcherOptions options;
  options.max_angle_deg = 5.0;  // as above
  options.max_waves = 1;        // so that the adaptive patches leave ground
  PatchEngine engine(*kernels, group, options);
  Propagator propagator(group, options, engine);
  propagator.RunSeeds(seeds);
  propagator.RunWaves({});
  const size_t adaptive_points = propagator.points().size();
  const size_t adaptive_patches = propagator.patches().size();
  ASSERT_GT(adaptive_patches, 0u);
  ASSERT_GT(adaptive_points, 2 * adaptive_patches);  // several points a patch

  const MatcherOptions pmvs_options = PmvsPassOptions(options);
  PatchEngine pmvs_engine(*kernels, group, pmvs_options);
  propagator.GrowAsPmvs(pmvs_engine);
  propagator.Prune(std::vector<bool>(adaptive_points, true));
  ASSERT_EQ(propagator.points().size(), adaptive_points);
  options.max_waves = 4;  // the propagator's options: three waves more
  propagator.RunWaves({});
  const std::vector<AcceptedPatch>& patches = propagator.patches();
  const std::vector<DensePoint>& points = propagator.points();
  ASSERT_GT(patches.size(), adaptive_patches);
  std::vector<int> emitted(patches.size(), 0);
  for (size_t i = adaptive_points; i < points.size(); ++i) {
    const DensePoint& d = points[i];
    ASSERT_GE(d.patch, static_cast<int>(adaptive_patches)) << "an adaptive patch emitted again";
    ++emitted[d.patch];
    const AcceptedPatch& patch = patches[d.patch];
    EXPECT_EQ(patch.size, options.window_size);
    EXPECT_LT((d.x - patch.center).norm(), 1e-9);
    // Within a footprint (about 0.5 m here) of the ground, z = 0.
    EXPECT_LT(std::abs(d.x.z()), 0.5) << "point " << i;
  }
  for (size_t p = adaptive_patches; p < patches.size(); ++p) EXPECT_EQ(emitted[p], 1) << p;
  // The first of them lie beside the adaptive points: some reference cell
  // of an adaptive point is a 4-neighbour of the first one-cell patch's.
  const Camera& cam = scene.cameras[patches[adaptive_patches].ref];
  const Eigen::Vector2d uv = cam.Project(patches[adaptive_patches].center);
  const int cs = options.cell_size;
  const int gx = static_cast<int>(std::floor((uv.x() + 0.5) / cs));
  const int gy = static_cast<int>(std::floor((uv.y() + 0.5) / cs));
  bool beside = false;
  for (size_t i = 0; i < adaptive_points && !beside; ++i) {
    if (patches[points[i].patch].ref != patches[adaptive_patches].ref) continue;
    const int px = static_cast<int>(std::floor((points[i].uv.x() + 0.5) / cs));
    const int py = static_cast<int>(std::floor((points[i].uv.y() + 0.5) / cs));
    beside = std::abs(px - gx) + std::abs(py - gy) == 1;
  }
  EXPECT_TRUE(beside);
}

// The references of the one-cell patches a pmvs pass grows in two waves
// from the adaptive patches of seeds in image 0 (one wave), on a strip of
// three images 2 m apart at 40 m (2.9 degrees). Images 1 and 2 may be
// references while the pass's first rims are offered (Prune) and in its
// waves, or not.
std::map<int, int> PmvsPassRefs(test::PlaneScene& scene, PatchKernels& kernels,
                                double max_angle_deg, bool views_reference_at_start,
                                bool views_reference_in_waves) {
  MatchGroupData group = GroupWithGrey(scene);
  auto views_reference = [&](bool reference) {
    for (size_t i = 1; i < group.images.size(); ++i) group.images[i].reference = reference;
  };
  views_reference(views_reference_at_start);
  MatcherOptions options;
  options.max_angle_deg = max_angle_deg;
  options.max_waves = 1;
  PatchEngine engine(kernels, group, options);
  Propagator propagator(group, options, engine);
  propagator.RunSeeds(SeedsInImage0(scene, 4));
  propagator.RunWaves({});
  const size_t adaptive_points = propagator.points().size();
  const size_t adaptive_patches = propagator.patches().size();
  EXPECT_GT(adaptive_patches, 0u);
  for (const AcceptedPatch& p : propagator.patches()) EXPECT_EQ(p.ref, 0);
  const MatcherOptions pmvs_options = PmvsPassOptions(options);  // the engine keeps a reference
  PatchEngine pmvs_engine(kernels, group, pmvs_options);
  propagator.GrowAsPmvs(pmvs_engine);
  propagator.Prune(std::vector<bool>(adaptive_points, true));
  views_reference(views_reference_in_waves);
  options.max_waves = 3;  // the propagator's options: two waves more
  propagator.RunWaves({});
  std::map<int, int> refs;
  const std::vector<AcceptedPatch>& patches = propagator.patches();
  for (size_t p = adaptive_patches; p < patches.size(); ++p) ++refs[patches[p].ref];
  std::printf("[ measured ] one-cell patches by reference: 0: %d, 1: %d, 2: %d\n",
              refs.count(0) ? refs.at(0) : 0, refs.count(1) ? refs.at(1) : 0,
              refs.count(2) ? refs.at(2) : 0);
  return refs;
}

// A pmvs pass also offers each patch's rims in its views, with the view as
// reference (Propagator::OfferInViews): the adaptive patches grown from
// seeds in image 0 alone leave one-cell patches in images 1 and 2 too;
// none where those images are view-only (another strip's), or where they
// meet image 0 at less than 2 max_angle_deg.
TEST(Propagator, APmvsPassGrowsFromItsRimsInItsViewsToo) {
  test::PlaneScene scene = test::MakePlaneScene(3, 121, 97, 17, 2.0);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  const std::map<int, int> wide = PmvsPassRefs(scene, *kernels, 1.0, true, true);
  EXPECT_GT(wide.count(0), 0u);
  EXPECT_TRUE(wide.count(1) || wide.count(2));
  for (const auto& [ref, n] : PmvsPassRefs(scene, *kernels, 1.0, false, false)) {
    EXPECT_EQ(ref, 0) << n;
  }
  for (const auto& [ref, n] : PmvsPassRefs(scene, *kernels, 2.0, true, true)) {
    EXPECT_EQ(ref, 0) << n;
  }
}

// ... and each new patch's rims in its views at every wave (Expand), as
// PMVS2 expands a patch in every image it is seen in. With images 1 and 2
// references only once the pass's first rims are offered (in image 0
// alone), their one-cell patches can only come from the waves' rims in the
// views. Still none where the views meet image 0 at less than 2
// max_angle_deg.
TEST(Propagator, APmvsPassGrowsInItsViewsAtEveryWave) {
  test::PlaneScene scene = test::MakePlaneScene(3, 121, 97, 17, 2.0);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  const std::map<int, int> wide = PmvsPassRefs(scene, *kernels, 1.0, false, true);
  EXPECT_GT(wide.count(0), 0u);
  EXPECT_TRUE(wide.count(1) || wide.count(2));
  for (const auto& [ref, n] : PmvsPassRefs(scene, *kernels, 2.0, false, true)) {
    EXPECT_EQ(ref, 0) << n;
  }
}

}  // namespace
}  // namespace sapmvs

namespace sapmvs {
namespace {

// A group that owns part of the ground grows only there: seeds and
// candidates whose centres lie outside its region are not tried, so no
// patch centre lies outside it (but for the refinement's move along its
// ray, a few centimetres here), while without a region the same seeds
// cover both sides. The region's edge runs through the middle of image 0's
// ground, in the block's world frame (the group's origin added).
// In a group larger than a view list, an image that sees a patch's ground
// though not among its views has its cells there claimed too (within the
// widest of the patch's views), so that it does not match that ground again
// as a reference: a strip of 5 where images 0 and 1, both holding seeds of
// the same ground, match in the far pair (3 and 4) only.
TEST(Propagator, ImagesBeyondTheViewListDoNotMatchTheSameGroundAgain) {
  test::PlaneScene scene = test::MakePlaneScene(5, 121, 97, 17, /*strip_base=*/3.0);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  std::vector<SeedFeature> seeds = SeedsInImage0(scene, 8);
  for (size_t k = 0, n = seeds.size(); k < n; ++k) {
    SeedFeature f = seeds[k];
    f.image = 1;
    f.uv = scene.cameras[1].Project(f.candidates[0].center);
    f.candidates[0].ref = 1;
    seeds.push_back(f);
  }
  MatcherOptions options;
  options.max_angle_deg = 5.0;  // neighbours 3 m apart at 40 m: 4.3 degrees
  options.max_waves = 4;
  // Points of references 0 and 1 that land on an image-0 pixel that a point
  // of the other one landed on: the same ground matched twice.
  auto twice = [&](bool far_pair_only, long* points) {
    MatchGroupData group = GroupWithGrey(scene);
    if (far_pair_only) group.images[0].views = group.images[1].views = {3, 4};
    PatchEngine engine(*kernels, group, options);
    Propagator propagator(group, options, engine);
    propagator.RunSeeds(seeds);
    propagator.RunWaves({});
    std::map<std::pair<long, long>, int> by;  // image-0 pixel -> bit per reference
    for (const DensePoint& d : propagator.points()) {
      const int ref = propagator.patches()[d.patch].ref;
      const Eigen::Vector2d uv = scene.cameras[0].Project(d.x);
      if (ref <= 1) by[{std::lround(uv.x()), std::lround(uv.y())}] |= 1 << ref;
    }
    *points = static_cast<long>(propagator.points().size());
    return std::count_if(by.begin(), by.end(), [](const auto& b) { return b.second == 3; });
  };
  long all_points = 0, far_points = 0;
  const long all_views = twice(false, &all_points);
  const long far_pair = twice(true, &far_points);
  ASSERT_GT(far_points, 1000);
  EXPECT_LE(far_pair, all_views + far_points / 50);
}

TEST(Propagator, GrowsOnlyOnTheGroundItOwns) {
  test::PlaneScene scene = test::MakePlaneScene(3, 121, 97, 17);
  MatchGroupData group = GroupWithGrey(scene);
  group.origin = Eigen::Vector3d(500000, 5400000, 200);
  const std::vector<SeedFeature> seeds = SeedsInImage0(scene, 12);
  const std::unique_ptr<PatchKernels> kernels = MakeReferencePatchKernels({"reference"});
  MatcherOptions options;
  options.max_angle_deg = 5.0;  // the cameras are a few metres apart at 40 m
  options.max_waves = 6;
  const Eigen::Vector3d middle = test::GroundAt(scene.cameras[0], {60, 48});
  const double x0 = group.origin.x() + middle.x();
  auto run = [&](const GroundRegion& region, long* left, long* right) {
    PatchEngine engine(*kernels, group, options);
    Propagator propagator(group, options, engine);
    propagator.SetRegion(region);
    propagator.RunSeeds(seeds);
    propagator.RunWaves({});
    *left = *right = 0;
    for (const AcceptedPatch& p : propagator.patches()) {
      const double x = group.origin.x() + p.center.x();
      *left += x < x0 - 0.1;
      *right += x > x0 + 0.1;
    }
  };
  long left = 0, right = 0;
  run(GroundRegion(), &left, &right);
  ASSERT_GT(left, 10);
  ASSERT_GT(right, 10);
  // Two centres 20 m either side of x0: the first owns x <= x0.
  const std::vector<Eigen::Vector2d> centers = {{x0 - 20, group.origin.y()},
                                                {x0 + 20, group.origin.y()}};
  run(GroundRegion(centers, 0, 0), &left, &right);
  EXPECT_GT(left, 10);
  EXPECT_EQ(right, 0);
  run(GroundRegion(centers, 1, 0), &left, &right);
  EXPECT_EQ(left, 0);
  EXPECT_GT(right, 10);
}

}  // namespace
}  // namespace sapmvs

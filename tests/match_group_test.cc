#include "sapmvs/match/match_group.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "cl_test_fixture.h"
#include "device/cl_patch_kernels.h"
#include "device/ncc_scorer.h"
#include "match/edge_matcher.h"
#include "match/group_data.h"
#include "match/patch_engine.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/evaluate/surface_check.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// ---- Options -------------------------------------------------------------

// Check() logs its first failing condition; the tests keep stderr quiet.
bool CheckQuietly(const MatcherOptions& o) {
  ::testing::internal::CaptureStderr();
  const bool ok = o.Check();
  ::testing::internal::GetCapturedStderr();
  return ok;
}

// Runs Check() and returns what it logged.
std::string CheckMessage(const MatcherOptions& o) {
  ::testing::internal::CaptureStderr();
  o.Check();
  return ::testing::internal::GetCapturedStderr();
}

TEST(MatcherOptions, DefaultsPassCheckInBothModes) {
  MatcherOptions o;
  EXPECT_TRUE(CheckQuietly(o)) << CheckMessage(o);
  EXPECT_EQ(o.adaptive_sizes.back(), o.window_size);
  o.mode = MatchMode::kPmvs;
  EXPECT_TRUE(CheckQuietly(o)) << CheckMessage(o);
  EXPECT_TRUE(CheckMessage(MatcherOptions{}).empty());
}

TEST(MatcherOptions, BadValuesFailCheckNamingTheValue) {
  struct Case {
    const char* what;
    void (*set)(MatcherOptions&);
    const char* names;  // Check() names this in its message
  };
  const Case cases[] = {
      {"even window_size", [](MatcherOptions& o) { o.window_size = 8; }, "window_size"},
      {"window_size 1", [](MatcherOptions& o) { o.window_size = 1; }, "window_size"},
      {"adaptive_sizes not ending with window_size",
       [](MatcherOptions& o) {
         o.adaptive_sizes = {21, 15, 11};
       },
       "adaptive_sizes"},
      {"adaptive_sizes empty", [](MatcherOptions& o) { o.adaptive_sizes.clear(); },
       "adaptive_sizes"},
      {"adaptive_sizes increasing",
       [](MatcherOptions& o) {
         o.adaptive_sizes = {11, 15, 7};
       },
       "adaptive_sizes"},
      {"adaptive_sizes even",
       [](MatcherOptions& o) {
         o.adaptive_sizes = {21, 16, 7};
       },
       "adaptive_sizes"},
      {"min_image_num 1", [](MatcherOptions& o) { o.min_image_num = 1; }, "min_image_num"},
      {"threshold_before > threshold",
       [](MatcherOptions& o) {
         o.threshold = 0.5;
         o.threshold_before = 0.6;
       },
       "threshold_before"},
      {"threshold above 1", [](MatcherOptions& o) { o.threshold = 1.5; }, "threshold"},
      {"level -1", [](MatcherOptions& o) { o.level = -1; }, "level"},
      {"cell_size 0", [](MatcherOptions& o) { o.cell_size = 0; }, "cell_size"},
      {"max_angle_deg 90", [](MatcherOptions& o) { o.max_angle_deg = 90; }, "max_angle_deg"},
      {"view_angle_deg NaN", [](MatcherOptions& o) { o.view_angle_deg = std::nan(""); },
       "view_angle_deg"},
      {"features_per_block 0", [](MatcherOptions& o) { o.features_per_block = 0; },
       "features_per_block"},
      {"first_features_per_block -1", [](MatcherOptions& o) { o.first_features_per_block = -1; },
       "first_features_per_block"},
      {"visibility_only_filters 10", [](MatcherOptions& o) { o.visibility_only_filters = 10; },
       "visibility_only_filters"},
      {"epipolar_distance 0", [](MatcherOptions& o) { o.epipolar_distance = 0; },
       "epipolar_distance"},
      {"max_wave 0", [](MatcherOptions& o) { o.max_wave = 0; }, "max_wave"},
      {"min_cluster_size -1", [](MatcherOptions& o) { o.min_cluster_size = -1; },
       "min_cluster_size"},
  };
  for (const Case& c : cases) {
    MatcherOptions o;
    c.set(o);
    const std::string message = CheckMessage(o);
    EXPECT_FALSE(CheckQuietly(o)) << c.what;
    EXPECT_NE(message.find(c.names), std::string::npos) << c.what << ": " << message;
    EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << c.what << ": " << message;
  }
}

TEST(MatcherOptions, PmvsModeIgnoresAdaptiveSizes) {
  MatcherOptions o;
  o.mode = MatchMode::kPmvs;
  o.adaptive_sizes = {21, 15, 11};
  EXPECT_TRUE(CheckQuietly(o)) << CheckMessage(o);
  o.mode = MatchMode::kSapmvs;
  EXPECT_FALSE(CheckQuietly(o));
}

TEST(MatchMode, ParsesAndPrintsBothModes) {
  EXPECT_EQ(ParseMatchMode("sapmvs"), MatchMode::kSapmvs);
  EXPECT_EQ(ParseMatchMode("pmvs"), MatchMode::kPmvs);
  EXPECT_EQ(ParseMatchMode(ToString(MatchMode::kSapmvs)), MatchMode::kSapmvs);
  EXPECT_EQ(ParseMatchMode(ToString(MatchMode::kPmvs)), MatchMode::kPmvs);
}

TEST(MatchMode, UnknownModeThrowsNamingIt) {
  for (const std::string bad : {"x", "PMVS", "", "sapmvs "}) {
    try {
      ParseMatchMode(bad);
      ADD_FAILURE() << "no error for '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("'" + bad + "'"), std::string::npos) << e.what();
    }
  }
}

// ---- End to end on the simulated tiny block -------------------------------

class MatchGroupTest : public test::ClTest {
 public:
  struct Measured {
    MatchResult result;
    SurfaceCheck check;
    SurfaceCheck random_check;  // a random cloud of the same size and extent
    double near = 0;            // share within 2 GSD of the true surface in 3D, walls included
    double near_level = 0;      // the same within 2 GSD of the level matched (versus_pmvs2's)
    double gsd = 0;             // block GSD (level 0)
  };

 protected:
  // The tiny preset, simulated once per test process (in-process, ~6 s).
  static fs::path TinyDir() { return test::Simulated("tiny", 1); }

  static MatcherOptions Options(MatchMode mode) {
    MatcherOptions o;
    o.mode = mode;
    if (mode == MatchMode::kPmvs) o.adaptive_sizes = {o.window_size};
    o.min_image_num = 2;  // 4 images in 2 strips
    o.progress = false;
    return o;
  }

  Measured MatchAndCheck(const MatcherOptions& options) {
    Measured m;
    const Block block = ReadBlock(TinyDir() / "block.yaml");
    const auto kernels = MakeClPatchKernels(context());
    m.result = MatchGroup(block, {}, options, *kernels);
    const GeoRaster dsm = ReadGeoRaster(TinyDir() / "truth" / "dsm.tif");
    m.gsd = EstimateBlockGeometry(block).gsd_median;
    SurfaceCheckOptions so;
    so.tolerance = 2 * m.gsd;
    so.cell_size = 4 * m.result.stats.gsd;  // the working level's GSD
    so.min_images = options.min_image_num;
    m.check = CheckAgainstSurface(m.result.cloud, dsm, block, so);
    if (!m.result.cloud.points.empty()) {
      m.near = ShareNearSurface(m.result.cloud, dsm, 2 * m.gsd);
      m.near_level = ShareNearSurface(m.result.cloud, dsm, 2 * m.result.stats.gsd);
    }
    // Control: as many points, uniformly over the cloud's bounding box.
    PointCloud random;
    if (!m.result.cloud.points.empty()) {
      Eigen::Vector3d lo = m.result.cloud.points[0].position, hi = lo;
      for (const CloudPoint& p : m.result.cloud.points) {
        lo = lo.cwiseMin(p.position);
        hi = hi.cwiseMax(p.position);
      }
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> unit(0, 1);
      for (size_t i = 0; i < m.result.cloud.points.size(); ++i) {
        CloudPoint p;
        p.position = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
        random.points.push_back(p);
      }
    }
    m.random_check = CheckAgainstSurface(random, dsm, block, so);
    const MatchStats& s = m.result.stats;
    std::printf(
        "[ measured ] %s: %ld points (%ld before filter), share within 2 GSD %.4f, median |dz| "
        "%.4f m = %.3f GSD, coverage %.4f (%ld of %ld cells of %.3f m); random cloud: share "
        "%.4f, coverage %.4f; block GSD %.4f m, level GSD %.4f m\n",
        ToString(options.mode).c_str(), s.points, s.points_before_filter, m.check.share_within,
        m.check.median_abs_dz, m.check.median_abs_dz / m.gsd, m.check.coverage,
        m.check.cells_covered, m.check.cells_seen, so.cell_size, m.random_check.share_within,
        m.random_check.coverage, m.gsd, s.gsd);
    return m;
  }

  // Every point is well formed and passed the options' thresholds.
  static void ExpectPointsWellFormed(const PointCloud& cloud, const MatcherOptions& o) {
    EXPECT_TRUE(cloud.has_normals);
    EXPECT_TRUE(cloud.has_colors);
    EXPECT_TRUE(cloud.has_scores);
    EXPECT_TRUE(cloud.has_views);
    long bad = 0;
    for (size_t i = 0; i < cloud.points.size(); ++i) {
      const CloudPoint& p = cloud.points[i];
      const bool ok = p.position.allFinite() && p.normal.allFinite() &&
                      std::abs(p.normal.norm() - 1.0f) < 1e-3f && p.num_views >= o.min_image_num &&
                      p.num_views <= 4 && std::isfinite(p.score) && p.score >= o.threshold - 1e-6 &&
                      p.score <= 1.0f + 1e-6f;
      if (!ok && ++bad <= 5) {
        ADD_FAILURE() << "point " << i << ": (" << p.position.transpose() << "), normal ("
                      << p.normal.transpose() << "), views " << p.num_views << ", score "
                      << p.score;
      }
    }
    EXPECT_EQ(bad, 0);
  }

  // Each point's colour is the colour at its projection into one of the
  // group's images at the matched level (its reference's, read again from
  // the file once the points are known), interpolated bilinearly and
  // rounded: a sapmvs-mode point lies on a pixel, a pmvs-mode point at its
  // cell's centre, a pixel corner. A colour from another image or place of
  // these textured renderings, or one of the pixels around a corner, would
  // match only by chance.
  static void ExpectColoursFromTheirImages(const PointCloud& cloud, int level) {
    const Block block = ReadBlock(TinyDir() / "block.yaml");
    const MatchGroupData group = LoadMatchGroup(block, {0, 1, 2, 3}, level, nullptr);
    std::vector<cv::Mat> colors;
    for (const MatchImage& im : group.images) colors.push_back(LoadColorAtLevel(block, im, level));
    long found = 0;
    for (const CloudPoint& p : cloud.points) {
      const Eigen::Vector3d x = p.position - group.origin;
      bool any = false;
      for (size_t i = 0; i < group.images.size() && !any; ++i) {
        const Camera& camera = group.images[i].camera;
        const Eigen::Vector2d uv = camera.Project(x);
        if (!camera.InImage(uv)) continue;
        cv::Mat bgr;  // OpenCV's bilinear sampling, border pixels repeated
        cv::getRectSubPix(colors[i], cv::Size(1, 1), cv::Point2f(uv.x(), uv.y()), bgr, CV_32F);
        const cv::Vec3f want = bgr.at<cv::Vec3f>(0, 0);
        // Rounded to 8 bits: half a level, and a hair for the float32
        // projection at a pixel corner.
        any = std::abs(want[2] - p.color[0]) <= 0.51 && std::abs(want[1] - p.color[1]) <= 0.51 &&
              std::abs(want[0] - p.color[2]) <= 0.51;
      }
      found += any;
    }
    std::printf("[ colours  ] %ld of %zu points have their image's colour\n", found,
                cloud.points.size());
    EXPECT_GE(found, 0.99 * static_cast<double>(cloud.points.size()));
  }
};

// Acceptance floors against truth/dsm.tif. Measured on PoCL (tiny preset,
// seed 1, level 1, min_image_num 2, default options):
//   sapmvs: 55909 points, share within 2 GSD 0.906, median |dz| 0.300 GSD,
//           coverage 0.700;
//   pmvs:   14464 points, share within 2 GSD 0.967, median |dz| 0.230 GSD,
//           coverage 0.710;
//   a random cloud of the same size and extent: share 0.02 to 0.05,
//   coverage 0.06 to 0.11.
// The previous filter (plane tolerance 1.5 footprints, no score fence, no
// free-space test) measured shares of 0.774 / 0.871 with coverage 0.763 /
// 0.785: the share floors fail with it. The floors sit below the
// measurements by a margin for PoCL builds on other CPUs.
struct Floors {
  long points;
  double share_within;
  double median_abs_dz_gsd;  // upper bound, block GSDs
  double coverage;
};

void ExpectMeetsFloors(const MatchGroupTest::Measured& m, const Floors& f) {
  EXPECT_GE(m.result.stats.points, f.points);
  EXPECT_GE(m.check.share_within, f.share_within);
  EXPECT_LT(m.check.median_abs_dz, f.median_abs_dz_gsd * m.gsd);
  EXPECT_GE(m.check.coverage, f.coverage);
  // The floors mean something: a random cloud is far below them.
  EXPECT_LT(m.random_check.share_within, 0.5 * f.share_within);
  EXPECT_LT(m.random_check.coverage, 0.5 * f.coverage);
}

TEST_F(MatchGroupTest, SapmvsModeMatchesTheTrueSurface) {
  const MatcherOptions o = Options(MatchMode::kSapmvs);
  SCOPED_TRACE("mode " + ToString(o.mode));
  const Measured m = MatchAndCheck(o);
  const MatchStats& s = m.result.stats;
  EXPECT_EQ(s.points, static_cast<long>(m.result.cloud.points.size()));
  EXPECT_EQ(s.images, 4);
  EXPECT_NEAR(s.gsd, 2 * m.gsd, 0.2 * m.gsd);  // level 1
  EXPECT_GT(s.seeds_accepted, 0);
  EXPECT_GT(s.patches, 0);
  // Every adaptive size is a size the patches may take.
  for (const auto& [size, count] : s.accepted_by_size) {
    EXPECT_NE(std::find(o.adaptive_sizes.begin(), o.adaptive_sizes.end(), size),
              o.adaptive_sizes.end())
        << size;
  }
  ExpectMeetsFloors(m, {30000, 0.85, 0.45, 0.58});
  ExpectPointsWellFormed(m.result.cloud, o);
  ExpectColoursFromTheirImages(m.result.cloud, o.level);
}

TEST_F(MatchGroupTest, PmvsModeMatchesTheTrueSurface) {
  const MatcherOptions o = Options(MatchMode::kPmvs);
  SCOPED_TRACE("mode " + ToString(o.mode));
  const Measured m = MatchAndCheck(o);
  const MatchStats& s = m.result.stats;
  EXPECT_EQ(s.points, static_cast<long>(m.result.cloud.points.size()));
  EXPECT_EQ(s.images, 4);
  EXPECT_NEAR(s.gsd, 2 * m.gsd, 0.2 * m.gsd);  // level 1
  EXPECT_GT(s.seeds_accepted, 0);
  // One window size only.
  for (const auto& [size, count] : s.accepted_by_size) EXPECT_EQ(size, o.window_size);
  ExpectMeetsFloors(m, {8000, 0.9, 0.4, 0.63});
  ExpectPointsWellFormed(m.result.cloud, o);
  ExpectColoursFromTheirImages(m.result.cloud, o.level);
}

// The group's grey images lie in one page-aligned block, one after the
// other with their rows packed, where the kernels' image buffer puts them;
// PoCL's CPU device reads that block in place instead of a copy.
TEST_F(MatchGroupTest, GreyImagesArePackedInOneBlockTheDeviceReadsInPlace) {
  const Block block = ReadBlock(TinyDir() / "block.yaml");
  const MatchGroupData group = LoadMatchGroup(block, {0, 1, 2, 3}, 1, nullptr);
  ASSERT_NE(group.ncc.pixels, nullptr);
  EXPECT_EQ(reinterpret_cast<uintptr_t>(group.ncc.pixels.get()) % 4096, 0u);
  size_t offset = 0;
  for (size_t i = 0; i < group.images.size(); ++i) {
    const cv::Mat& grey = group.images[i].grey;
    ASSERT_EQ(grey.type(), CV_32F);
    EXPECT_TRUE(grey.isContinuous());
    EXPECT_EQ(grey.ptr<float>(), group.ncc.pixels.get() + offset) << "image " << i;
    EXPECT_EQ(group.ncc.images[i].data, grey.ptr<float>()) << "image " << i;
    offset += grey.total();
  }
  const NccDeviceGroup device = UploadNccGroup(context(), group.ncc);
  if (!context().device().host_unified_memory) {
    GTEST_SKIP() << context().device().name << " has memory of its own: the images are copied";
  }
  EXPECT_EQ(device.pixels.get(), group.ncc.pixels.get());
}

// The paper's edge barriers (--edges, off by default): the edges matched
// along epipolar lines lie on the true surface, and a run with them keeps
// the floors of a run without.
TEST_F(MatchGroupTest, MatchedEdgesLieOnTheSurfaceAndBarriersKeepTheFloors) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  o.use_edges = true;
  const Block block = ReadBlock(TinyDir() / "block.yaml");
  MatchGroupData group = LoadMatchGroup(block, {0, 1, 2, 3}, o.level, nullptr);
  SelectViews(o, &group);
  const auto kernels = MakeClPatchKernels(context());
  PatchEngine engine(*kernels, group, o);
  // Depths from the truth's height range, padded by 10 %: the seeds' range
  // that MatchGroup gives is tested through the run below.
  const GeoRaster dsm = ReadGeoRaster(TinyDir() / "truth" / "dsm.tif");
  float lo = INFINITY, hi = -INFINITY;
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      if (dsm.IsEmpty(c, r)) continue;
      lo = std::min(lo, dsm.at(c, r));
      hi = std::max(hi, dsm.at(c, r));
    }
  }
  std::vector<std::pair<double, double>> ranges;
  for (const MatchImage& im : group.images) {
    const double h = im.camera.center().z() + group.origin.z();
    ranges.emplace_back(0.9 * (h - hi), 1.1 * (h - lo));
  }
  EdgeMatchStats stats;
  const std::vector<EdgeMap> maps = MatchEdges(group, o, ranges, engine, &stats);
  ASSERT_EQ(maps.size(), group.images.size());
  PointCloud edges;
  for (const EdgeMap& m : maps) {
    for (const auto& [pixel, x] : m.points) {
      CloudPoint c;
      c.position = x.cast<double>() + group.origin;
      edges.points.push_back(c);
    }
  }
  EXPECT_GT(stats.edge_pixels, 1000);
  EXPECT_EQ(stats.matched, static_cast<long>(edges.points.size()));
  EXPECT_GT(stats.matched, stats.edge_pixels / 20);
  SurfaceCheckOptions so;
  so.tolerance = 2 * EstimateBlockGeometry(block).gsd_median;
  so.cell_size = 4 * so.tolerance;
  so.min_images = 2;
  const SurfaceCheck check = CheckAgainstSurface(edges, dsm, block, so);
  std::printf("[ measured ] %ld of %ld edge pixels matched, %.3f within 2 GSD of the surface\n",
              stats.matched, stats.edge_pixels, check.share_within);
  // Measured 0.49 (1,357 of 24,450 edge pixels matched); a random cloud of
  // the scene's extent scores about 0.05. Edges lie on roof rims, where the
  // truth's flat-topped cells make a point a pixel off the rim read the
  // ground's height, so the share of well-matched edges is higher.
  EXPECT_GT(check.share_within, 0.35);

  const Measured m = MatchAndCheck(o);
  EXPECT_GT(m.result.stats.matched_edge_points, 0);
  ExpectMeetsFloors(m, {30000, 0.85, 0.45, 0.58});
}

// A patch is tried at a larger size only where its plane already scores
// grow_threshold there: the higher the bar, the fewer large patches, none at
// a bar no noisy window reaches; 0 is PMVS's threshold_before, the most.
TEST_F(MatchGroupTest, LargerSizesAreTriedWhereThePlaneAlreadyScoresTheGrowThreshold) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  auto large = [](const MatchStats& s, int window) {
    long n = 0;
    for (const auto& [size, count] : s.accepted_by_size) n += size > window ? count : 0;
    return n;
  };
  std::vector<long> counts;
  for (const double bar : {0.0, 0.9, 1.0}) {
    o.grow_threshold = bar;
    const Measured m = MatchAndCheck(o);
    counts.push_back(large(m.result.stats, o.window_size));
    std::printf("[ measured ] grow_threshold %.1f: %ld large patches\n", bar, counts.back());
  }
  EXPECT_GT(counts[0], counts[1]);
  EXPECT_GT(counts[1], 0);
  EXPECT_EQ(counts[2], 0);
}

// PMVS's expand-filter loop: the passes after the first grow the surviving
// patches into the cells the filter freed, which covers more of the ground.
TEST_F(MatchGroupTest, LaterPassesGrowIntoTheCellsTheFilterFreed) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  o.pmvs_passes = 0;  // adaptive passes only
  o.expand_iterations = 1;
  const Measured one = MatchAndCheck(o);
  o.expand_iterations = 3;
  const Measured three = MatchAndCheck(o);
  EXPECT_GT(three.result.stats.points_before_filter, one.result.stats.points_before_filter);
  EXPECT_GT(three.result.stats.waves, one.result.stats.waves);
  EXPECT_GT(three.result.stats.points, one.result.stats.points);
  EXPECT_GT(three.check.cells_covered, one.check.cells_covered);
  // Filtered like the first pass's points, the new ones keep the accuracy.
  EXPECT_GT(three.check.share_within, one.check.share_within - 0.03);
  // The passes' times add up under one stage name each.
  int propagation = 0;
  for (const auto& [name, t] : three.result.stats.stages) propagation += name == "propagation";
  EXPECT_EQ(propagation, 1);
}

// Seeding in two tiers: the first features of each block seed the first
// waves, the rest only the cells those left empty. Fewer seeds are tried
// than when all seed at once, more than with the first tier alone, for the
// same surface.
TEST_F(MatchGroupTest, LateSeedsTryOnlyWhatTheFirstWavesLeftEmpty) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  ASSERT_GT(o.first_features_per_block, 0);
  ASSERT_LT(o.first_features_per_block, o.features_per_block);
  const Measured tiers = MatchAndCheck(o);
  o.first_features_per_block = 0;
  const Measured at_once = MatchAndCheck(o);
  o.features_per_block = MatcherOptions{}.first_features_per_block;
  const Measured first_only = MatchAndCheck(o);
  std::printf("[ measured ] seeds tried: %ld in two tiers, %ld at once, %ld first tier only\n",
              tiers.result.stats.seeds_tried, at_once.result.stats.seeds_tried,
              first_only.result.stats.seeds_tried);
  EXPECT_LT(tiers.result.stats.seeds_tried, 0.9 * at_once.result.stats.seeds_tried);
  EXPECT_GT(tiers.result.stats.seeds_tried, first_only.result.stats.seeds_tried);
  EXPECT_GT(tiers.check.cells_covered, 0.98 * at_once.check.cells_covered);
  EXPECT_GT(tiers.check.share_within, at_once.check.share_within - 0.01);
}

// The first pass's filter testing scores and visibility only: its
// neighbourhood failures go at the second pass's filter, for the same
// surface. The last pass's filter tests all whatever the option says.
TEST_F(MatchGroupTest, AnEarlyFilterOfScoresAndVisibilityKeepsTheSurface) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  ASSERT_GE(o.expand_iterations, 2);
  o.visibility_only_filters = 1;
  const Measured light = MatchAndCheck(o);
  o.visibility_only_filters = 0;
  const Measured full = MatchAndCheck(o);
  o.visibility_only_filters = 9;
  const Measured all_light = MatchAndCheck(o);
  std::printf("[ measured ] cells covered %ld light first, %ld full; within 2 GSD %.4f, %.4f\n",
              light.check.cells_covered, full.check.cells_covered, light.check.share_within,
              full.check.share_within);
  EXPECT_NE(light.result.stats.points_before_filter, full.result.stats.points_before_filter);
  EXPECT_GT(light.check.cells_covered, 0.98 * full.check.cells_covered);
  EXPECT_GT(light.check.share_within, full.check.share_within - 0.01);
  EXPECT_GT(all_light.result.stats.removed_neighbourhood, 0);
  EXPECT_GT(all_light.check.share_within, full.check.share_within - 0.03);
}

// The last pass growing one-cell patches as PMVS does, in place of a third
// adaptive one, covers ground the adaptive patches left at their accuracy
// in 3D, within 2 GSD of the level matched (versus_pmvs2's unit). Its points
// on walls lie far from the DSM's height there, so the vertical test counts
// them as wrong (on `tiny` 97.8 -> 94.7 % within 2 block GSD); and those
// whose views resolve their depth to 2 footprints may lie that far off
// their neighbours' plane (pmvs_pass_plane_tolerance), so within 2 block
// GSD (1 of the level) in 3D they fall 99.0 -> 97.9 %.
TEST_F(MatchGroupTest, APmvsPassCoversMoreAtTheSameAccuracy) {
  MatcherOptions o = Options(MatchMode::kSapmvs);
  o.pmvs_passes = 0;
  const Measured adaptive = MatchAndCheck(o);
  o.pmvs_passes = 1;
  const Measured last = MatchAndCheck(o);
  EXPECT_EQ(adaptive.result.stats.pmvs_pass_patches, 0);
  EXPECT_GT(last.result.stats.pmvs_pass_patches, 0);
  EXPECT_GT(last.check.cells_covered, adaptive.check.cells_covered);
  EXPECT_GT(last.near_level, adaptive.near_level - 0.01);
  std::printf(
      "[ measured ] within 2 GSD of the truth in 3D: %.4f without the pmvs pass, %.4f with; "
      "within 2 GSD of the level matched %.4f, %.4f\n",
      adaptive.near, last.near, adaptive.near_level, last.near_level);
  // Their fence is their own: plain NCC over one 7 x 7 window scores below
  // the adaptive patches' weighted NCC, right matches included.
  EXPECT_EQ(adaptive.result.stats.pmvs_pass_score_floor, 0);
  EXPECT_GE(last.result.stats.pmvs_pass_score_floor, o.threshold);
  EXPECT_LT(last.result.stats.pmvs_pass_score_floor, last.result.stats.score_floor);
  // Their launches are counted with the others of the same size.
  EXPECT_GT(last.result.stats.kernels.at("patch_refine 7x7").items,
            adaptive.result.stats.kernels.at("patch_refine 7x7").items);
}

// The NGI aerial block at full resolution: the cloud follows the DEM, with no
// gross errors. Before the seed-depth fences in MatchGroup, 229 points of a
// false cluster sat 3.3 to 4.1 km below the ground here.
class MatchRealBlockTest : public test::ClTest {};

TEST_F(MatchRealBlockTest, NgiCloudFollowsTheDemWithoutGrossErrors) {
  const std::filesystem::path yaml = test::TestDir() / "blocks" / "ngi.yaml";
  const std::filesystem::path dem_path =
      test::SharedDir() / "datasets" / "orthority_ngi_odm" / "ngi" / "dem.tif";
  if (!std::filesystem::exists(dem_path)) GTEST_SKIP() << "no " << dem_path;
  const Block block = ReadBlock(yaml);
  MatcherOptions o;
  o.level = 0;
  o.progress = false;
  const auto kernels = MakeClPatchKernels(context());
  const MatchResult r = MatchGroup(block, {}, o, *kernels);
  const GeoRaster dem = ReadGeoRaster(dem_path);
  const double gsd = EstimateBlockGeometry(block).gsd_median;  // about 6 m
  std::vector<double> abs_dz;
  double worst = 0;
  for (const CloudPoint& p : r.cloud.points) {
    const int col = static_cast<int>((p.position.x() - dem.origin_x) / dem.cell_size);
    const int row = static_cast<int>((dem.origin_y - p.position.y()) / dem.cell_size);
    if (col < 0 || row < 0 || col >= dem.width || row >= dem.height || dem.IsEmpty(col, row)) {
      continue;
    }
    const double dz = std::abs(p.position.z() - dem.at(col, row));
    abs_dz.push_back(dz);
    worst = std::max(worst, dz);
  }
  ASSERT_GT(abs_dz.size(), 10000u);
  std::nth_element(abs_dz.begin(), abs_dz.begin() + abs_dz.size() / 2, abs_dz.end());
  const double median = abs_dz[abs_dz.size() / 2];
  std::printf(
      "[ measured ] NGI level 0: %zu points on the DEM, median |dz| %.2f m (%.2f GSD), "
      "worst %.1f m\n",
      abs_dz.size(), median, median / gsd, worst);
  // The DEM is bare ground at 24 m cells; buildings and trees stand above it.
  EXPECT_LT(median, gsd);
  EXPECT_LT(worst, 25 * gsd);  // 150 m: far above any building here
}

}  // namespace
}  // namespace sapmvs

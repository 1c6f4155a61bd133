#include "sapmvs/match/match_group.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "match/edge_matcher.h"
#include "match/feature_detector.h"
#include "match/group_data.h"
#include "match/patch_engine.h"
#include "match/patch_filter.h"
#include "match/propagation.h"
#include "match/seed_matcher.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/cpu_time.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/memory_use.h"
#include "sapmvs/util/parallel_for.h"
#include "sapmvs/util/progress.h"
#include "util/run_progress.h"

namespace sapmvs {
namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Every kernel of the engines summed: device seconds and NCC evaluations.
KernelTime KernelTotals(const std::vector<const PatchEngine*>& engines) {
  KernelTime sum;
  for (const PatchEngine* engine : engines) {
    for (const auto& [name, t] : engine->kernel_times()) AddKernelTime(t, &sum);
  }
  return sum;
}

// The colour at `uv` of an 8-bit BGR image, bilinear between the pixels
// around it (border pixels repeated), as RGB. A sapmvs-mode point lies on a
// pixel and takes that pixel's colour; a pmvs-mode point lies at its cell's
// centre, a pixel corner, where rounding to one of the four pixels picked
// whichever the float32 projection fell nearer.
std::array<uint8_t, 3> ColourAt(const cv::Mat& bgr, const Eigen::Vector2f& uv) {
  const Eigen::Vector3d c = BilinearBgr(bgr, uv.x(), uv.y());
  return {static_cast<uint8_t>(std::lround(c[2])), static_cast<uint8_t>(std::lround(c[1])),
          static_cast<uint8_t>(std::lround(c[0]))};
}

}  // namespace

MatcherMemoryModel MatcherMemory() {
  const double views = kMaxViews - 1;
  const KernelBatchBytes batch = PatchKernelBatchBytes();
  MatcherMemoryModel m;
  // grouping.h EstimateGroupMemory spells out each term.
  m.device_bytes_per_pixel = sizeof(float);
  m.host_bytes_per_pixel = sizeof(float) + 1;
  // Fitted, not summed: the patches and points a pixel ends up with, and
  // the filter's arrays over them, depend on how much of the images matches
  // (0.007 to 0.17 points a pixel on the blocks below). Counted on the
  // pixels that can take points only (EstimateGroupMemory's cell_shares:
  // not a view's, not outside a footprint group's tile), and per pixel, not
  // per cell, as points are emitted per pixel: 13 bytes put every group of
  // `small`, `city`, `campus`, Herz-Jesu-P8, the Caliterra flight and
  // simulated 12 MP flights of 20 and 60 images within -12 to +15 % of its
  // measured peak, and `tiny` at level 0 with cells of 2 and of 1 pixel
  // +10 and +5 % (profiling/results/memory.md).
  m.host_bytes_per_point_pixel = 13;
  m.device_bytes_per_candidate = batch.per_patch + views * batch.per_pair;
  m.host_bytes_per_candidate =
      sizeof(PatchCandidate) + sizeof(std::optional<AcceptedPatch>) + 4 * views;
  m.runtime_warmup_bytes = 24.0 * (1 << 20);
  return m;
}

MatchResult MatchGroup(const Block& block, const std::vector<int>& image_ids,
                       const MatcherOptions& options, PatchKernels& kernels,
                       const BlockGeometry* geometry, const MatchProgressFn& on_progress,
                       const std::vector<int>& view_ids, const GroundRegion& region,
                       const LevelImageStore* levels) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("matcher options: expected " + problem);
  std::vector<int> ids = image_ids;
  if (ids.empty()) {
    for (size_t i = 0; i < block.images.size(); ++i) ids.push_back(static_cast<int>(i));
  }
  // The kernels' programs build (30 ms each on PoCL, 8 of them; 2 ms each
  // from the binary cache of earlier runs) on another core while this one
  // loads the images, detects features and matches seeds; the engine, which
  // launches them, waits for it. Nothing else calls `kernels` until then.
  struct Joined {
    std::thread thread;
    ~Joined() {
      if (thread.joinable()) thread.join();
    }
  } prepare;
  prepare.thread = std::thread([&kernels, variants = EngineKernelVariants(options)] {
    try {
      kernels.Prepare(variants.scorers, variants.refiners);
    } catch (...) {  // a launch that needs what failed reports it
    }
  });
  MatchResult result;
  MatchStats& stats = result.stats;
  // Without a caller's display, a one-group status line of our own.
  std::optional<RunProgress> own;
  if (!on_progress && options.progress && Progress::TerminalAllowsProgress()) {
    own.emplace(1, static_cast<long>(ids.size()), true);
    own->StartGroup(0, 1, static_cast<long>(ids.size()));
  }
  auto report = [&](const std::string& stage, long done = 0, long total = 0,
                    const std::string& detail = "") {
    const MatchProgressEvent e{stage, done, total, detail};
    if (on_progress) on_progress(e);
    if (own) own->Update(e);
  };
  report("load");
  auto stage_start = std::chrono::steady_clock::now();
  KernelTime kernels_before;
  double cpu_before = ProcessCpuSeconds();
  std::vector<const PatchEngine*> engines;  // those launched so far
  auto end_stage = [&](const std::string& name) {
    StageTime t;
    t.wall = Seconds(stage_start);
    const KernelTime kernels_now = KernelTotals(engines);
    t.device = kernels_now.seconds - kernels_before.seconds;
    t.ncc_evaluations = kernels_now.ncc_evaluations - kernels_before.ncc_evaluations;
    kernels_before = kernels_now;
    const double cpu_now = ProcessCpuSeconds();
    t.cpu = cpu_now - cpu_before;
    cpu_before = cpu_now;
    // The group's peak so far, which only grows: the later pass's is the higher.
    t.peak_rss_bytes = PeakRssBytes();
    AddStageTime(name, t, &stats.stages);
    stage_start = std::chrono::steady_clock::now();
  };

  const size_t references = ids.size();
  ids.insert(ids.end(), view_ids.begin(), view_ids.end());
  MatchGroupData group = LoadMatchGroup(block, ids, options.level, geometry, levels);
  for (size_t i = references; i < group.images.size(); ++i) group.images[i].reference = false;
  SelectViews(options, &group);
  stats.images = static_cast<int>(group.images.size());
  stats.gsd = group.gsd;
  end_stage("load");
  report("features");

  const int largest = options.mode == MatchMode::kSapmvs
                          ? std::max(options.window_size, options.adaptive_sizes.front())
                          : options.window_size;
  const int margin = largest / 2 + 1;
  // One image per thread: OpenCV's filters here hardly use a second core.
  // Their buffers, made afresh for each image, are reused (ScopedHeapReuse):
  // as new mappings, their page faults were two thirds of the stage's time
  // (Herz-Jesu-P8: 1.0-1.35 s against 0.34-0.37 s). On this thread, not in
  // another's arena (RunWithHeapReuse): glibc does not trim a thread arena's
  // top, and what it kept lifted Herz-Jesu-P8's peak by 14 MiB; here the
  // scope's end hands the main heap's free pages back.
  std::vector<std::vector<Feature>> features(group.images.size());
  {
    const ScopedHeapReuse reuse;
    ParallelFor(
        static_cast<long>(group.images.size()),
        [&](long i) {
          features[i] = DetectFeatures(group.images[i].grey, options.features_per_block, margin);
        },
        1);
  }
  for (const std::vector<Feature>& f : features) stats.features += static_cast<long>(f.size());
  end_stage("features");

  report("seeds", 0, 0, "epipolar candidates");
  // The features after the first first_features_per_block of each block
  // seed only the cells the first pass's waves leave empty.
  const bool late_seeds = options.mode == MatchMode::kSapmvs &&
                          options.first_features_per_block > 0 &&
                          options.first_features_per_block < options.features_per_block &&
                          options.pmvs_passes < options.expand_iterations;
  std::vector<SeedFeature> seeds = MatchSeeds(group, features, options, [&](int, const Feature& f) {
    return !late_seeds || f.block_rank < options.first_features_per_block;
  });
  report("seeds", 0, 0, "building kernels");
  prepare.thread.join();
  PatchEngine engine(kernels, group, options);
  engines.push_back(&engine);
  Propagator propagator(group, options, engine);
  propagator.SetRegion(region);
  propagator.RunSeeds(seeds, [&](long rank, long ranks, long accepted) {
    report("seeds", rank, ranks, std::to_string(accepted) + " accepted");
  });
  // Their candidates (14 MB on `city`) would otherwise stay through the
  // filter, where a group's run peaks.
  std::vector<SeedFeature>().swap(seeds);
  if (!late_seeds) std::vector<std::vector<Feature>>().swap(features);
  end_stage("seeds");

  // Per image, the depths its accepted seeds span (5th to 95th percentile),
  // padded by `share` of that span plus `gsds` ground sample distances;
  // (0, 0) when an image has fewer than 10 seeds.
  auto seed_depth_ranges = [&](double share, double gsds) {
    std::vector<std::pair<double, double>> ranges(group.images.size(), {0.0, 0.0});
    for (size_t i = 0; i < group.images.size(); ++i) {
      std::vector<double> d = propagator.seed_depths()[i];
      if (d.size() < 10) continue;
      std::sort(d.begin(), d.end());
      const double lo = d[d.size() / 20], hi = d[d.size() - 1 - d.size() / 20];
      const double pad = share * (hi - lo) + gsds * group.gsd;
      ranges[i] = {lo - pad, hi + pad};
    }
    return ranges;
  };
  if (options.mode == MatchMode::kSapmvs && options.use_edges) {
    report("edges");
    const auto ranges = seed_depth_ranges(0.25, 2.0);
    EdgeMatchStats es;
    propagator.SetEdges(MatchEdges(group, options, ranges, engine, &es));
    stats.edge_points = es.edge_pixels;
    stats.matched_edge_points = es.matched;
    end_stage("edges");
  }

  std::vector<double> search_near(group.images.size());
  for (size_t i = 0; i < group.images.size(); ++i) {
    search_near[i] = kSeedDepthMin * group.images[i].depth;
  }
  const std::vector<std::pair<double, double>> plausible =
      SeedDepthFences(propagator.seed_depths(), search_near, group.gsd);
  const auto& points = propagator.points();
  const auto& patches = propagator.patches();
  std::vector<bool> keep;
  // The engine of the passes that grow as PMVS does (pmvs_passes), made at
  // the first of them.
  const MatcherOptions pmvs_pass_options = PmvsPassOptions(options);
  std::optional<PatchEngine> pmvs_pass_engine;
  PatchClasses classes;  // their patches from classes.one_cell_first on
  // PMVS's loop: expand, filter, and expand again into the ground the
  // filter freed; every pass filters all points, old and new.
  for (int pass = 0; pass < options.expand_iterations; ++pass) {
    const bool as_pmvs = options.mode == MatchMode::kSapmvs &&
                         pass >= options.expand_iterations - options.pmvs_passes;
    const bool first_pmvs_pass = as_pmvs && !pmvs_pass_engine;
    if (first_pmvs_pass) {
      pmvs_pass_engine.emplace(kernels, group, pmvs_pass_options, PatchEngine::Role::kOneCellPass);
      engines.push_back(&*pmvs_pass_engine);
      classes.one_cell_first = patches.size();
      propagator.GrowAsPmvs(*pmvs_pass_engine);
      // Every pass PMVS's (pmvs_passes = expand_iterations): the seeds'
      // rims, in place of their adaptive expansions.
      if (pass == 0) keep.assign(points.size(), true);
    }
    if (pass > 0 || as_pmvs) propagator.Prune(keep);
    auto on_wave = [&](const std::string& what) {
      return [&, what](long wave, long size, long emitted) {
        report("propagation", pass + 1, options.expand_iterations,
               what + " " + std::to_string(wave) + ", " + std::to_string(size) + " candidates, " +
                   std::to_string(emitted) + " points");
      };
    };
    propagator.RunWaves(on_wave(as_pmvs ? "pmvs wave" : "wave"));
    if (late_seeds && pass == 0) {
      report("propagation", 1, options.expand_iterations, "late seeds");
      std::vector<SeedFeature> late =
          MatchSeeds(group, features, options, [&](int image, const Feature& f) {
            return f.block_rank >= options.first_features_per_block &&
                   propagator.CellFree(image, f.uv);
          });
      std::vector<std::vector<Feature>>().swap(features);
      propagator.RunSeeds(late);
      std::vector<SeedFeature>().swap(late);
      propagator.RunWaves(on_wave("wave"));
    }
    // One-cell patches emit their centres only: nothing to refit.
    if (!as_pmvs) {
      const long cut = propagator.RefitPlanes();
      stats.removed_unfitted += cut;
      if (cut > 0 && options.refill_cut) {
        propagator.RunWaves(on_wave("refill wave"));
        stats.removed_unfitted += propagator.RefitPlanes();
      }
    }
    end_stage("propagation");
    report("filter", pass + 1, options.expand_iterations);

    // The fence, from the scores of the points of the first expansion; the
    // pmvs passes' one-cell patches score on another scale, so theirs comes
    // from their own first pass.
    if (pass == 0) stats.score_floor = ScoreFloor(options, points, patches);
    if (first_pmvs_pass) {
      classes.one_cell_floor = ScoreFloor(options, points, patches, classes.one_cell_first);
      stats.pmvs_pass_score_floor = classes.one_cell_floor;
    }
    classes.floor = stats.score_floor;
    // The filter's neighbour table makes each pass's peak, which is the
    // group's. The waves' threads freed many small blocks (emit plans, flood
    // fills, batches) that glibc keeps in their arenas and in the heap's
    // holes: on `city` 10-12 MiB of that peak, handed back here.
    ReleaseFreeMemory();
    MatchStats removed;
    const bool light =
        options.mode == MatchMode::kSapmvs &&
        pass < std::min(options.visibility_only_filters, options.expand_iterations - 1);
    keep = FilterPoints(group, options, points, patches, &removed, classes,
                        light ? FilterTests::kScoreAndVisibility : FilterTests::kAll);
    stats.removed_depth_range += ApplyDepthFences(group, points, patches, plausible, &keep);
    stats.removed_score += removed.removed_score;
    stats.plane_tolerance = removed.plane_tolerance;
    stats.removed_visibility += removed.removed_visibility;
    stats.removed_neighbourhood += removed.removed_neighbourhood;
    stats.removed_clusters += removed.removed_clusters;
    end_stage("filter");
  }
  stats.seeds_tried = propagator.seeds_tried();
  stats.seeds_accepted = propagator.seeds_accepted();
  stats.candidates = propagator.candidates();
  stats.waves = propagator.waves();
  stats.largest_wave = propagator.largest_wave();
  stats.points_before_filter = propagator.emitted();
  stats.patches = static_cast<long>(patches.size());
  if (pmvs_pass_engine) {
    stats.pmvs_pass_patches = static_cast<long>(patches.size() - classes.one_cell_first);
  }
  for (const AcceptedPatch& p : patches) ++stats.accepted_by_size[p.size];

  PointCloud& cloud = result.cloud;
  cloud.has_normals = cloud.has_colors = cloud.has_scores = cloud.has_views = true;
  cloud.crs = block.crs;
  cloud.points.reserve(std::count(keep.begin(), keep.end(), true));
  std::vector<bool> has_points(group.images.size(), false);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!keep[i]) continue;
    const DensePoint& d = points[i];
    const AcceptedPatch& p = patches[d.patch];
    CloudPoint c;
    c.position = d.x + group.origin;
    c.normal = p.normal.cast<float>();
    c.score = p.score;
    c.num_views = 1 + static_cast<int>(p.views.size());
    cloud.points.push_back(c);
    has_points[p.ref] = true;
  }
  // The colours, from each reference image read again (from the run's store
  // of images at the level where there is one, else its file): held
  // from the load on, the colour images were 3 bytes a pixel of the level
  // through the whole matching (38 MiB of Herz-Jesu-P8's 382 MiB peak), for
  // a read here that costs what the load's did (0.42 s on Herz-Jesu-P8).
  // kImagesReadAtOnce at a time, as the load reads them: each holds its
  // full-resolution pixels, and an undistorted copy, while it reads (the
  // plan counts that many such images). Each point takes its colour from
  // its reference image only, so the images' writes never meet.
  std::vector<size_t> point_of(points.size());
  for (size_t i = 0, j = 0; i < points.size(); ++i) point_of[i] = keep[i] ? j++ : 0;
  ParallelFor(
      static_cast<long>(group.images.size()),
      [&](long r) {
        if (!has_points[r]) return;
        const cv::Mat color = LoadColorAtLevel(block, group.images[r], options.level, levels);
        for (size_t i = 0; i < points.size(); ++i) {
          const DensePoint& d = points[i];
          if (keep[i] && patches[d.patch].ref == r)
            cloud.points[point_of[i]].color = ColourAt(color, d.uv);
        }
      },
      1, kImagesReadAtOnce);
  stats.points = static_cast<long>(cloud.points.size());
  stats.kernels = engine.kernel_times();
  if (pmvs_pass_engine) {
    // Under the same names: their launches are 7 x 7 scores and refinements.
    for (const auto& [name, t] : pmvs_pass_engine->kernel_times()) {
      AddKernelTime(t, &stats.kernels[name]);
    }
  }
  end_stage("output");
  if (own) own->Finish();
  return result;
}

}  // namespace sapmvs

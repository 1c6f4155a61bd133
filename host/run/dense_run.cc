#include "sapmvs/run/dense_run.h"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <sstream>

#include "device/make_patch_kernels.h"
#include "match/device_spec.h"
#include "match/patch_kernels.h"
#include "run/group_dispatch.h"
#include "run/merged_outputs.h"
#include "run/mpi_session.h"
#include "run/ortho_outputs.h"
#include "run/run_checkpoint.h"
#include "run/run_report.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/level_images.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/ortho/true_ortho.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/report/report_html.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/run/cloud_las.h"
#include "sapmvs/run/cloud_merge.h"
#include "sapmvs/run/dsm_picture.h"
#include "sapmvs/util/byte_size.h"
#include "sapmvs/util/cpu_time.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/log.h"
#include "sapmvs/util/memory_use.h"
#include "sapmvs/util/number_text.h"
#include "sapmvs/util/output_folder.h"
#include "sapmvs/util/progress.h"
#include "util/run_progress.h"

namespace sapmvs {

namespace {

double Since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

std::string Seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f s", s);
  return buf;
}

void AddStats(const MatchStats& s, MatchStats* sum) {
  sum->images += s.images;
  sum->features += s.features;
  sum->seeds_tried += s.seeds_tried;
  sum->seeds_accepted += s.seeds_accepted;
  sum->edge_points += s.edge_points;
  sum->matched_edge_points += s.matched_edge_points;
  sum->candidates += s.candidates;
  sum->patches += s.patches;
  sum->pmvs_pass_patches += s.pmvs_pass_patches;
  sum->waves += s.waves;
  sum->largest_wave = std::max(sum->largest_wave, s.largest_wave);
  for (const auto& [size, n] : s.accepted_by_size) sum->accepted_by_size[size] += n;
  sum->points_before_filter += s.points_before_filter;
  // A run's floor and tolerance: the highest of its groups' (each group has
  // its own).
  sum->score_floor = std::max(sum->score_floor, s.score_floor);
  sum->pmvs_pass_score_floor = std::max(sum->pmvs_pass_score_floor, s.pmvs_pass_score_floor);
  sum->removed_score += s.removed_score;
  sum->plane_tolerance = std::max(sum->plane_tolerance, s.plane_tolerance);
  sum->removed_visibility += s.removed_visibility;
  sum->removed_neighbourhood += s.removed_neighbourhood;
  sum->removed_clusters += s.removed_clusters;
  sum->removed_depth_range += s.removed_depth_range;
  sum->removed_unfitted += s.removed_unfitted;
  sum->points += s.points;
  for (const auto& [name, t] : s.stages) AddStageTime(name, t, &sum->stages);
  for (const auto& [name, k] : s.kernels) AddKernelTime(k, &sum->kernels[name]);
  sum->gsd = s.gsd;
}

// A group finished by an earlier call or another rank, as its checkpoint
// records it.
void TakeCheckpoint(const GroupCheckpoint& c, GroupRun* run) {
  run->points = c.points;
  run->seconds = c.seconds;
  run->memory = c.memory;
}

RunReport RunGroups(const RunOptions& options, GroupDispatch& dispatch) {
  dispatch.Start();
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("run: expected " + problem);
  // Everything that can be refused is checked before the first file is
  // written, so a failed start leaves nothing that stops the corrected
  // command: the folder, the block and its CRS, the device.
  if (dispatch.merges()) OutputFolder::Check(options.out, "run");
  const auto start = std::chrono::steady_clock::now();
  RunReport report;
  report.out = options.out;
  report.start_time = std::chrono::system_clock::now();
  auto stage_start = start;
  double stage_cpu = ProcessCpuSeconds();
  // A stage's peak without resetting the high-water mark (which would make
  // the peak that `time` or a parent's wait4 sees the last stage's): exact
  // where the stage raised the mark, unknown (NaN) where it stayed below an
  // earlier peak. The match stage resets it for each group (below), so its
  // peak is the largest of theirs.
  double groups_peak = 0, mark_before = 0;
  auto end_stage = [&](const std::string& name) {
    const double cpu = ProcessCpuSeconds();
    const double mark = PeakRssBytes();
    const double peak = groups_peak > 0 ? groups_peak : mark > mark_before ? mark : kNaN;
    report.stages.push_back({name, Since(stage_start), cpu - stage_cpu, peak});
    groups_peak = 0;
    mark_before = mark;
    LogDetail("run: " + name + " " + Seconds(report.stages.back().wall));
    stage_start = std::chrono::steady_clock::now();
    stage_cpu = cpu;
  };

  const Block block = ReadBlock(options.block, options.read);
  // What cloud.las and the DSM rasters will need, after the matching:
  // checked while the block's geometry is estimated.
  GeoOutputsCheck geo_outputs(block.crs, block.source.string());
  report.images = static_cast<int>(block.images.size());
  const BlockGeometry geometry = EstimateBlockGeometry(block);
  geo_outputs.Wait();
  // Without a GSD the merge radius would be 0, found only after matching.
  if (const std::string reason = NoSurfaceReason(block, geometry); !reason.empty()) {
    throw Error(reason);
  }
  // The device before the plan, which counts its runtime's memory; after the
  // geometry, whose DEM would otherwise add to the runtime's peak.
  PatchKernelsOptions kernel_options;
  kernel_options.device = DeviceForLocalRank(options.device, dispatch.session().local_rank());
  kernel_options.profile = options.profile;
  std::unique_ptr<PatchKernels> kernels = MakePatchKernels(kernel_options);
  {
    // Scoped: `kernels` is released once the matching ends.
    const KernelDevice& device = kernels->device();
    report.device = device.description;
    report.device_info = {device.name, device.vendor, device.platform, device.type};
  }
  LogDetail("device: " + report.device);

  // What the process holds before any group, once what planning freed is
  // handed back: every group's estimate adds it (rank 0's under mpirun, so
  // that the ranks' plans agree).
  ReleaseFreeMemory();
  const GroupingPlan plan =
      PlanGroups(block, options.grouping, options.matcher, &geometry,
                 dispatch.PlanProcessBytes(CurrentRssBytes() + GdalBytesToMatch(block)));
  report.strategy = plan.single_group ? "single group" : ToString(plan.strategy);
  for (const int i : plan.ungrouped) report.ungrouped.push_back(block.images[i].name);
  end_stage("plan");

  // Under mpirun rank 0 alone takes the folder and its lock, and writes
  // plan.json, while the others wait in dispatch.Start().
  std::unique_ptr<OutputFolder> folder;
  if (dispatch.merges()) {
    folder = std::make_unique<OutputFolder>(options.out, "run",
                                            std::vector<std::filesystem::path>{"groups"});
    if (options.restart) RemoveRunOutputs(options.out);
  }
  const bool owns_ground = plan.groups.size() > 1 && !options.share_ground;
  RunCheckpoints checkpoints(
      options.out / "groups", block, plan, options.matcher, options.restart && dispatch.merges(),
      owns_ground ? std::optional<double>(options.own_margin_gsd) : std::nullopt);
  dispatch.Open(options.out / "groups");
  report.ranks = dispatch.session().size();
  report.rank = dispatch.session().rank();

  const bool show =
      options.matcher.progress && dispatch.merges() && Progress::TerminalAllowsProgress();
  const int n = static_cast<int>(plan.groups.size());
  // The groups this call will match, for the ETA: not checkpointed, and at
  // most max_groups of them.
  int to_match = 0;
  long images_to_match = 0;
  for (int g = 0; g < n; ++g) {
    if (checkpoints.Done(g) || (options.max_groups > 0 && to_match >= options.max_groups)) continue;
    ++to_match;
    images_to_match += static_cast<long>(plan.groups[g].images.size());
  }
  RunProgress progress(to_match, images_to_match, show);
  std::vector<Eigen::Vector2d> centers;
  for (const ImageGroup& group : plan.groups)
    centers.push_back(group.center + block.origin.head<2>());
  const double level_gsd = geometry.gsd_median * std::ldexp(1.0, options.matcher.level);
  // The images at the level, decoded once for every group that reads them
  // and for the orthophoto; removed once the outputs are written (by rank 0,
  // which writes them, under mpirun).
  const LevelImageStore levels(options.out / "groups" / "levels");
  int matched_now = 0;
  bool stopped = false;  // groups left for a later call (max_groups)
  for (int g = 0; g < n; ++g) {
    GroupRun run;
    run.index = g;
    run.memory_estimate_bytes = plan.groups[g].memory.Total();
    for (const int i : plan.groups[g].images) run.images.push_back(block.images[i].name);
    if (checkpoints.Done(g)) {
      TakeCheckpoint(checkpoints.Read(g), &run);
      run.resumed = true;
      report.groups.push_back(run);
      continue;
    }
    if (options.max_groups > 0 && matched_now >= options.max_groups) {
      stopped = true;
      report.groups.push_back(run);
      continue;
    }
    if (!dispatch.Claim(g)) {  // another rank's
      report.groups.push_back(run);
      continue;
    }
    progress.StartGroup(g, n, static_cast<long>(plan.groups[g].images.size()));
    const auto t0 = std::chrono::steady_clock::now();
    ReleaseFreeMemory();  // what the groups before freed
    run.memory.rss_before_bytes = CurrentRssBytes();
    run.memory.peak_of_group = ResetPeakRss();
    kernels->ResetPeakDeviceBytes();
    MatchResult result = MatchGroup(
        block, plan.groups[g].images, options.matcher, *kernels, &geometry,
        [&](const MatchProgressEvent& e) { progress.Update(e); }, plan.groups[g].views,
        owns_ground ? GroundRegion(centers, g, options.own_margin_gsd * level_gsd) : GroundRegion(),
        &levels);
    run.seconds = Since(t0);
    run.points = static_cast<long>(result.cloud.points.size());
    run.memory.peak_rss_bytes = PeakRssBytes();
    run.memory.peak_device_bytes = kernels->PeakDeviceBytes();
    groups_peak = std::max(groups_peak, run.memory.peak_rss_bytes);
    progress.EndGroup(run.points, run.memory.peak_rss_bytes, run.memory_estimate_bytes);
    AddStats(result.stats, &report.stats);
    for (const auto& [name, t] : result.stats.stages) {
      LogDetail("group " + std::to_string(g + 1) + "/" + std::to_string(n) + ": " + name + " " +
                Seconds(t.wall) +
                (options.profile ? ", " + Seconds(t.device) + " in kernels" : ""));
    }
    checkpoints.Write(g, result.cloud, {run.points, run.seconds, run.memory}, result.stats,
                      options.profile);
    ++matched_now;
    report.groups.push_back(run);
  }
  progress.Finish();
  const std::vector<int> matched_by = dispatch.Finish(n);
  end_stage("match");
  // The device's buffers, queues and programs are not needed by the merge,
  // and the outputs' peak comes after it, once GDAL is loaded.
  kernels.reset();
  ReleaseFreeMemory();
  if (!dispatch.merges()) return report;
  // Also when the outputs fail: the copies are the run's scratch, not its.
  struct ClearLevels {
    const LevelImageStore& store;
    ~ClearLevels() { store.Clear(); }
  } clear_levels{levels};
  for (GroupRun& run : report.groups) {
    run.rank = report.ranks > 1 ? matched_by[run.index] : -1;
    if (run.rank <= 0 || !checkpoints.Done(run.index)) continue;
    TakeCheckpoint(checkpoints.Read(run.index), &run);  // matched by another rank
  }
  for (int g = 0; g < n; ++g) stopped = stopped || !checkpoints.Done(g);
  if (stopped) {
    report.total_seconds = Since(start);
    report.peak_rss_bytes = ProcessPeakRssBytes();
    return report;  // resumable
  }

  // Merge from the checkpoints, fresh or resumed alike, tile by tile.
  MergedOutputsJob job;
  for (int g = 0; g < n; ++g) {
    job.groups.push_back({[&checkpoints, g](const PointFilter& keep) {
                            return ReadPly(checkpoints.CloudPath(g), keep);
                          },
                          centers[g]});
  }
  job.merge.radius = options.merge_radius_gsd * level_gsd;
  // In radii: the heights are compared where both groups matched, within
  // their margin of the border.
  job.merge.seam_feather_radii = options.seam_feather_gsd / options.merge_radius_gsd;
  job.merge.blend_radii = options.seam_blend_gsd / options.merge_radius_gsd;
  job.merge.seam_band_radii = std::max(options.own_margin_gsd, 1.0) / options.merge_radius_gsd;
  job.merge.tile_points = options.merge_tile_points;
  job.dsm = options.dsm;
  job.las.version = options.las_version;
  job.las.crs = block.crs;
  job.crs = block.crs;
  job.out = options.out;
  job.block = options.block;
  RemoveRunEvaluation(options.out);
  const GeoRaster dsm = WriteMergedOutputs(job, &report, end_stage);
  if (!options.ortho.skip) {
    std::unique_ptr<Progress> bar;  // once the images to draw are known
    const TrueOrtho ortho = MakeTrueOrtho(
        block, dsm, options.matcher.level, options.ortho, level_gsd,
        [&](int done, int total) {
          if (!bar) bar = std::make_unique<Progress>("orthophoto", total, options.matcher.progress);
          bar->Advance(1, std::to_string(done) + "/" + std::to_string(total) + " images");
        },
        &levels);
    if (bar) bar->Finish();
    WriteOrthoOutputs(ortho, options.out);
    report.ortho_cell = ortho.grid.cell_size;
    report.ortho_width = ortho.grid.width;
    report.ortho_height = ortho.grid.height;
    report.ortho_filled_cells = ortho.filled_cells;
    report.ortho_images = ortho.images_used;
    report.ortho_objects = ortho.objects;
    end_stage("ortho");
  }
  report.finished = true;
  report.total_seconds = Since(start);
  report.peak_rss_bytes = ProcessPeakRssBytes();
  report.end_time = std::chrono::system_clock::now();
  WriteRunReport(options, report, block, plan);
  WriteReportHtml(options.out);
  return report;
}

}  // namespace

RunReport RunDense(const RunOptions& options) {
  MpiSession session;  // one process unless mpirun started this one
  GroupDispatch dispatch(session);
  if (session.size() == 1) return RunGroups(options, dispatch);
  // The other ranks would wait for this one forever: the first error ends
  // the job.
  try {
    return RunGroups(options, dispatch);
  } catch (const Error& e) {
    session.Abort(e.what(), e.ExitCode());
  } catch (const std::exception& e) {
    session.Abort(e.what(), 1);
  }
}

void PrintRunSummary(const RunReport& report, std::ostream& out) {
  const MatchStats& s = report.stats;
  out << "device        " << report.device << "\n";
  out << "groups        " << report.groups.size() << " (" << report.strategy << ")";
  if (report.ranks > 1) out << " on " << report.ranks << " MPI ranks";
  out << "\n";
  if (!report.ungrouped.empty()) {
    out << "ungrouped     " << report.ungrouped.size() << " images in no group (not matched):";
    for (const std::string& name : report.ungrouped) out << " " << name;
    out << "\n";
  }
  for (const GroupRun& g : report.groups) {
    out << "  group " << std::setw(3) << g.index + 1 << "  " << std::setw(2) << g.images.size()
        << " images  ";
    if (g.resumed) {
      out << std::setw(9) << g.points << " points  (checkpoint)";
    } else if (g.rank > 0) {
      out << std::setw(9) << g.points << " points  " << FormatHms(g.seconds) << " on rank "
          << g.rank;
    } else if (g.seconds > 0 || g.points > 0) {
      out << std::setw(9) << g.points << " points  " << FormatHms(g.seconds);
    }
    if (g.memory.peak_rss_bytes > 0) {
      out << "  peak " << FormatBytes(g.memory.peak_rss_bytes) << " (estimate "
          << FormatBytes(g.memory_estimate_bytes) << ")";
    }
    if (!g.resumed && g.seconds <= 0 && g.points <= 0) out << "          not run yet";
    out << "\n";
  }
  if (s.waves > 0) {
    out << "propagation   " << s.waves << " waves, " << s.candidates << " candidates, " << s.patches
        << " patches";
    if (!s.accepted_by_size.empty()) {
      out << " (";
      bool first = true;
      for (auto it = s.accepted_by_size.rbegin(); it != s.accepted_by_size.rend(); ++it) {
        out << (first ? "" : ", ") << it->first << "x" << it->first << ": " << it->second;
        first = false;
      }
      out << ")";
    }
    out << "\n";
  }
  out << std::fixed << std::setprecision(2);
  // The matching stages, then the run's own (its "match" is those summed).
  std::vector<std::pair<std::string, StageTime>> lines = s.stages;
  for (const RunReport::Stage& t : report.stages) {
    if (t.name != "match") lines.emplace_back(t.name, StageTime{t.wall, 0, t.cpu});
  }
  for (const auto& [name, t] : lines) {
    out << "time " << std::left << std::setw(12) << name << std::right << std::setw(8) << t.wall
        << " s wall";
    if (t.device > 0) out << ", " << t.device << " s in kernels";
    if (t.wall > 0 && t.cpu > 0) out << ", CPU/wall " << t.cpu / t.wall;
    if (t.peak_rss_bytes > 0)
      out << ", peak " << std::lround(t.peak_rss_bytes / (1 << 20)) << " MiB";
    out << "\n";
  }
  if (!report.finished) {
    out << "stopped       after the groups asked for; run again to resume\n";
    out.unsetf(std::ios::floatfield);
    return;
  }
  out << "merge         " << report.merge.input << " -> " << report.points << " points ("
      << report.merge.duplicates << " cross-group duplicates"
      << (report.merge.band_outliers > 0
              ? ", " + std::to_string(report.merge.band_outliers) + " off the border's surface"
              : "")
      << " dropped"
      << (report.merge_tiles > 1 ? ", " + std::to_string(report.merge_tiles) + " tiles" : "")
      << ")\n";
  out << "\n";
  out << "images  points      run time  avg. distance  density (pts/unit^2)\n";
  out << std::left << std::setw(8) << report.images << std::setw(12) << report.points
      << std::setw(10) << FormatHms(report.total_seconds) << std::right << std::setprecision(3)
      << std::setw(15) << report.mean_spacing << std::setw(22) << report.density << "\n\n";
  out << std::setprecision(2);
  out << "total         " << report.total_seconds << " s, peak memory "
      << report.peak_rss_bytes / (1 << 20) << " MiB\n";
  for (const char* f : {"cloud.ply", "cloud.las", "dsm.tif", "dsm_color.tif", "dsm.png", "dsm.pgw",
                        "ortho.tif", "ortho.png", "ortho.pgw", "report.json", "report.html"}) {
    if (std::string(f).rfind("ortho", 0) == 0 && report.ortho_cell == 0) continue;
    out << "wrote         " << (report.out / f).string() << "\n";
  }
  out.unsetf(std::ios::floatfield);
}

}  // namespace sapmvs

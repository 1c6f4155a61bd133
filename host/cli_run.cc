// `sapmvs run BLOCK --out DIR`: a whole block, grouped, matched, merged.
// Flags map one to one onto RunOptions / MatcherOptions / GroupingOptions /
// DsmOptions.
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "cli.h"
#include "run_profile.h"
#include "sapmvs/atomic_file.h"
#include "sapmvs/dense_run.h"
#include "sapmvs/error.h"

namespace sapmvs::cli {
namespace {

// The profile is written after the whole run: a folder that is not there
// must fail before the matching, not after it. DIR itself is made by the run.
void CheckProfilePath(const std::filesystem::path& csv, const std::filesystem::path& out) {
  std::error_code ec;
  const std::filesystem::path dir = csv.parent_path().empty() ? "." : csv.parent_path();
  if (std::filesystem::weakly_canonical(dir, ec) == std::filesystem::weakly_canonical(out, ec))
    return;
  try {
    AtomicFile check(csv);
  } catch (const Error& e) {
    throw Error(std::string("--profile ") + e.what());
  }
}

}  // namespace

void RegisterRunCommand(CLI::App& app, const GlobalFlags& global) {
  auto o = std::make_shared<RunOptions>();
  auto mode = std::make_shared<std::string>("sapmvs");
  auto no_edges = std::make_shared<bool>(false);
  auto strategy = std::make_shared<std::string>("strip");
  auto budget = std::make_shared<std::string>("8G");
  auto profile = std::make_shared<std::string>();
  auto las_version = std::make_shared<std::string>(ToString(o->las_version));
  auto block_flags = std::make_shared<BlockFlags>();
  MatcherOptions& m = o->matcher;
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Dense matching of a block: cloud.ply, cloud.las, dsm.tif, dsm_color.tif, dsm.png, "
      "report.json");
  cmd->option_defaults()->group("Input");
  cmd->add_option("block", o->block,
                  "Block: block.yaml, or a PMVS / COLMAP / Strecha / OpenSfM folder")
      ->required();
  cmd->option_defaults()->group("Output and resume");
  cmd->add_option("--out", o->out, "Output folder")->required();
  cmd->option_defaults()->group("Input");
  AddBlockFlags(cmd, block_flags.get());
  cmd->option_defaults()->group("Matching");
  cmd->add_option("--mode", *mode, "sapmvs (self-adaptive patch) or pmvs")->capture_default_str();
  cmd->option_defaults()->group("Device");
  cmd->add_option("--device", o->device,
                  "OpenCL device: index or name substring (see `sapmvs devices`), or "
                  "`reference` for the CPU reference (no OpenCL)");
  cmd->option_defaults()->group("Matching");
  cmd->add_option("--level", m.level, "Pyramid level: 0 full resolution, 1 half, ...")
      ->capture_default_str();
  cmd->add_option("--csize", m.cell_size, "Cell size, pixels at the level")->capture_default_str();
  cmd->add_option("--threshold", m.threshold, "NCC a view needs after optimisation")
      ->capture_default_str();
  cmd->add_option("--threshold-before", m.threshold_before, "NCC a view needs before optimisation")
      ->capture_default_str();
  cmd->add_option("--min-image-num", m.min_image_num, "Images a patch must be photo-consistent in")
      ->capture_default_str();
  cmd->add_option(
         "--max-angle", m.max_angle_deg,
         "PMVS2's maxAngle: some pair of a patch's images must meet at more than this, degrees")
      ->capture_default_str();
  cmd->add_option("--view-angle", m.view_angle_deg,
                  "Largest angle of a view to a patch normal, degrees")
      ->capture_default_str();
  cmd->add_option("--wsize", m.window_size, "Matching window, pixels (odd)")->capture_default_str();
  cmd->add_option("--adaptive-sizes", m.adaptive_sizes, "sapmvs patch sides, largest first")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option(
         "--ncc-sigma-color", m.ncc_sigma_color,
         "sapmvs: NCC sample weights, in SDs of the texture at the window's centre (0 = plain NCC)")
      ->capture_default_str();
  cmd->option_defaults()->group("Seeds and edges");
  cmd->add_option("--features-per-block", m.features_per_block,
                  "Features per detector per 32x32 block")
      ->capture_default_str();
  cmd->add_option("--epipolar-distance", m.epipolar_distance,
                  "Seed candidates: pixels from the epipolar line")
      ->capture_default_str();
  cmd->add_option("--candidates", m.candidates_per_feature, "Seed candidates tried per feature")
      ->capture_default_str();
  cmd->add_flag("--no-edges", *no_edges, "sapmvs: do not match edges (no propagation barriers)");
  cmd->option_defaults()->group("Propagation");
  cmd->add_option("--max-wave", m.max_wave, "Most candidates per device launch")
      ->capture_default_str();
  cmd->add_option("--max-waves", m.max_waves, "Stop after this many waves (0 = none)")
      ->capture_default_str();
  cmd->add_option("--expand-iterations", m.expand_iterations, "Expand-then-filter passes (PMVS: 3)")
      ->capture_default_str();
  cmd->option_defaults()->group("Filter");
  cmd->add_option(
         "--score-fence", m.score_fence,
         "Filter: robust SDs below the first pass's median score a point may lie (0 = off)")
      ->capture_default_str();
  cmd->add_option("--depth-tolerance", m.depth_tolerance,
                  "Filter: depth agreement, pixel footprints")
      ->capture_default_str();
  cmd->add_option("--neighbour-radius", m.neighbour_radius,
                  "Filter: neighbourhood radius, footprints")
      ->capture_default_str();
  cmd->add_option("--min-neighbours", m.min_neighbours, "Filter: neighbours a point needs")
      ->capture_default_str();
  cmd->add_option("--plane-tolerance", m.plane_tolerance,
                  "Filter: distance to the local plane, footprints")
      ->capture_default_str();
  cmd->add_option("--plane-sigmas", m.plane_sigmas,
                  "Filter: plane tolerance in robust SDs of the distances between patches")
      ->capture_default_str();
  cmd->add_option("--min-cluster", m.min_cluster_size, "Filter: smallest cluster kept, points")
      ->capture_default_str();
  cmd->option_defaults()->group("Grouping");
  cmd->add_option("--strategy", *strategy, "Grouping: strip (the paper) or footprint")
      ->capture_default_str();
  cmd->add_option("--max-images", o->grouping.max_images, "Most images per group")
      ->capture_default_str();
  cmd->add_option("--memory-budget", *budget, "Memory one group may use (8G, 512M, ...)")
      ->capture_default_str();
  cmd->option_defaults()->group("Output and resume");
  cmd->add_flag("--restart", o->restart, "Discard the checkpoints in DIR/groups and start over");
  cmd->add_option("--max-groups", o->max_groups,
                  "Match at most this many groups now, then stop (resumable; 0 = all)")
      ->capture_default_str();
  cmd->option_defaults()->group("Merge and DSM");
  cmd->add_option("--merge-radius", o->merge_radius_gsd,
                  "Merge: duplicate distance, GSDs of the level matched")
      ->capture_default_str();
  cmd->add_option("--dsm-cell", o->dsm.cell_size,
                  "DSM cell, CRS units (0 = twice the mean point spacing)")
      ->capture_default_str();
  cmd->add_option("--dsm-fill", o->dsm.fill_passes, "DSM gap-filling passes")
      ->capture_default_str();
  cmd->add_option("--las-version", *las_version,
                  "cloud.las: 1.2 (format 2, every reader opens it) or 1.4 (format 7)")
      ->capture_default_str();
  cmd->option_defaults()->group("Output and resume");
  CLI::Option* profile_option =
      cmd->add_option("--profile", *profile,
                      "Profile the kernels and phases: print tables, write FILE (CSV) and its "
                      ".json (default DIR/profile.csv)")
          ->expected(0, 1);
  cmd->footer(
      "Examples:\n"
      "  sapmvs run block.yaml --out out/run              SAPMVS at level 1, the defaults\n"
      "  sapmvs run block.yaml --out out/run --level 0    full resolution\n"
      "  sapmvs run colmap/sparse --out out/run --mode pmvs   PMVS's fixed 7x7 patch\n"
      "  sapmvs run block.yaml --out out/run --max-groups 1   one group now; the same\n"
      "                                                   command later resumes\n"
      "  sapmvs run block.yaml --out out/run --restart    discard the checkpoints\n"
      "Outputs in DIR: cloud.ply, cloud.las, dsm.tif, dsm_color.tif, dsm.png (+ .pgw),\n"
      "report.json, groups/.");
  cmd->callback([o, block_flags, mode, no_edges, strategy, budget, profile, profile_option,
                 las_version, &global] {
    o->read = ReadOptionsOf(*block_flags);
    o->profile = profile_option->count() > 0;
    o->grouping.strategy = ParseGroupingStrategy(*strategy);
    o->grouping.memory_budget = ParseByteSize(*budget);
    o->matcher.mode = ParseMatchMode(*mode);
    o->las_version = ParseLasVersion(*las_version);
    o->matcher.use_edges = !*no_edges;
    o->matcher.progress = !global.quiet;
    o->command_line = global.command_line;
    if (o->profile && !profile->empty()) CheckProfilePath(*profile, o->out);
    const RunReport report = RunDense(*o);
    PrintRunSummary(report, std::cout);
    if (o->profile) {
      PrintProfile(report, std::cout);
      const std::filesystem::path csv =
          profile->empty() ? o->out / "profile.csv" : std::filesystem::path(*profile);
      WriteProfile(report, csv);
      std::cout << "profile       " << csv.string() << " (and .json)\n";
    }
  });
}

}  // namespace sapmvs::cli

// `sapmvs run BLOCK --out DIR`: a whole block, grouped, matched, merged.
// Flags map one to one onto RunOptions / MatcherOptions / GroupingOptions /
// DsmOptions, from their descriptions (option_flags.h).
#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "cli/cli.h"
#include "run/mpi_session.h"
#include "run/run_profile.h"
#include "sapmvs/run/dense_run.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/thread_count.h"
#include "util/option_flags.h"

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
  auto profile = std::make_shared<std::string>();
  auto block_flags = std::make_shared<BlockFlags>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Dense matching of a block: cloud.ply, cloud.las, dsm.tif, dsm_color.tif, dsm.png, "
      "ortho.tif, ortho.png, report.json");
  cmd->option_defaults()->group("Input");
  cmd->add_option("block", o->block,
                  "Block: block.yaml, or a PMVS / COLMAP / Strecha / OpenSfM folder")
      ->required();
  cmd->add_option("--out", o->out, "Output folder")->required()->group("Output and resume");
  AddBlockFlags(cmd, block_flags.get());
  // The sections of --help come in the order of their first flag: the
  // device goes between the matching mode and the rest of the matcher's.
  AddOptionFlags(cmd, &o->matcher, {{"mode"}, {}});
  AddOptionFlags(cmd, o.get(), {{"device"}, {}});
  AddOptionFlags(cmd, &o->matcher, {{}, {"mode"}});
  AddOptionFlags(cmd, &o->grouping);
  AddOptionFlags(cmd, o.get(), {{}, {"device"}});
  AddOptionFlags(cmd, &o->dsm);
  AddOptionFlags(cmd, &o->ortho);
  CLI::Option* profile_option =
      cmd->add_option("--profile", *profile,
                      "Profile the kernels and phases: print tables, write FILE (CSV) and its "
                      ".json (default DIR/profile.csv)")
          ->expected(0, 1)
          ->group("Output and resume");
  cmd->footer(
      "Examples:\n"
      "  sapmvs run block.yaml --out out/run              SAPMVS at level 1, the defaults\n"
      "  sapmvs run block.yaml --out out/run --level 0    full resolution\n"
      "  sapmvs run colmap/sparse --out out/run --mode pmvs   PMVS's fixed 7x7 patch\n"
      "  sapmvs run block.yaml --out out/run --max-groups 1   one group now; the same\n"
      "                                                   command later resumes\n"
      "  sapmvs run block.yaml --out out/run --restart    discard the checkpoints\n"
      "  mpirun -np 2 sapmvs run block.yaml --out out/run --device 0,1\n"
      "                                                   groups over 2 processes, one GPU\n"
      "                                                   each (built with MPI); each rank\n"
      "                                                   takes the machine's cores divided\n"
      "                                                   by its ranks unless --threads N\n"
      "Outputs in DIR: cloud.ply, cloud.las, dsm.tif, dsm_color.tif, dsm.png (+ .pgw),\n"
      "ortho.tif, ortho.png (+ .pgw), report.json, groups/.");
  cmd->callback([o, block_flags, profile, profile_option, &global] {
    o->read = ReadOptionsOf(*block_flags);
    o->profile = profile_option->count() > 0;
    o->matcher.progress = !global.quiet;
    o->command_line = global.command_line;
    if (o->profile && !profile->empty()) CheckProfilePath(*profile, o->out);
    // Before the OpenCL platform is loaded, as ApplyGlobalFlags does.
    if (global.threads == 0) SetThreadCount(RankThreadCount());
    const RunReport report = RunDense(*o);
    if (report.rank != 0) return;  // rank 0 prints for the whole job
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

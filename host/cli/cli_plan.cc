// `sapmvs plan BLOCK`: how a block would be split into groups (method.md 2),
// without matching anything. Flags map one to one onto GroupingOptions and
// the MatcherOptions the plan depends on (PlanMatcherFields); the block flags
// are those of `sapmvs info`.

#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/cli.h"
#include "device/make_patch_kernels.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/memory_use.h"
#include "util/option_flags.h"

namespace sapmvs::cli {
namespace {

struct PlanArgs {
  std::string block;
  BlockFlags flags;
  GroupingOptions grouping;
  MatcherOptions matcher;
  std::string json;
};

}  // namespace

void RegisterPlanCommand(CLI::App& app, const GlobalFlags& /*global*/) {
  auto args = std::make_shared<PlanArgs>();
  CLI::App* cmd = app.add_subcommand(
      "plan", "Split a block into image groups (strips or ground tiles) and print the plan");
  cmd->add_option("block", args->block,
                  "Block: block.yaml, PMVS/COLMAP/Strecha folder, or OpenSfM json")
      ->required();
  AddOptionFlags(cmd, &args->grouping);
  AddOptionFlags(cmd, &args->matcher, PlanMatcherFields());
  cmd->add_option("--json", args->json, "Also write the plan as JSON to this file");
  AddBlockFlags(cmd, &args->flags);
  cmd->callback([args] {
    // Everything the user typed is checked before the block is read.
    for (const std::string& problem : {args->grouping.Problem(), args->matcher.Problem()}) {
      if (!problem.empty()) throw Error("plan: expected " + problem);
    }
    const BlockReadOptions read = ReadOptionsOf(args->flags);
    // A JSON path in a missing folder fails here, before the block is read.
    if (!args->json.empty()) AtomicFile check(args->json);
    const Block block = ReadBlock(args->block, read);
    const BlockGeometry geometry = EstimateBlockGeometry(block);
    // The estimates count what the matching process holds before its first
    // group; `run` holds the device's runtime too, so it is loaded here as
    // `run` would load it (SAPMVS_DEVICE or the default device), when there is one.
    std::unique_ptr<PatchKernels> kernels;
    try {
      kernels = MakePatchKernels(PatchKernelsOptions{});
    } catch (const NoDeviceError&) {
    }
    ReleaseFreeMemory();
    const GroupingPlan plan = PlanGroups(block, args->grouping, args->matcher, &geometry,
                                         CurrentRssBytes() + GdalBytesToMatch(block));
    PrintPlan(block, plan, std::cout);
    if (!args->json.empty()) {
      WriteTextAtomically(args->json, PlanToJson(block, plan).dump(2) + "\n");
      std::cout << "plan written to " << args->json << "\n";
    }
  });
}

}  // namespace sapmvs::cli

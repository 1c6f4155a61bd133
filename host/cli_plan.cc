// `sapmvs plan BLOCK`: how a block would be split into groups (method.md 2),
// without matching anything. Flags map one to one onto GroupingOptions; the
// block flags are those of `sapmvs info`.

#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "sapmvs/atomic_file.h"
#include "sapmvs/block_reader.h"
#include "sapmvs/error.h"
#include "sapmvs/grouping.h"

namespace sapmvs::cli {
namespace {

struct PlanArgs {
  std::string block;
  BlockFlags flags;
  GroupingOptions grouping;
  std::string strategy = "strip";
  std::string memory_budget = "8G";
  std::string json;
};

}  // namespace

void RegisterPlanCommand(CLI::App& app, const GlobalFlags& /*global*/) {
  auto args = std::make_shared<PlanArgs>();
  GroupingOptions& g = args->grouping;
  CLI::App* cmd = app.add_subcommand(
      "plan", "Split a block into image groups (strips or ground tiles) and print the plan");
  cmd->add_option("block", args->block,
                  "Block: block.yaml, PMVS/COLMAP/Strecha folder, or OpenSfM json")
      ->required();
  cmd->add_option("--strategy", args->strategy,
                  "strip (the paper: runs along flight strips) or footprint (ground tiles)")
      ->capture_default_str();
  cmd->add_option("--max-images", g.max_images, "Most images per group")->capture_default_str();
  cmd->add_option("--memory-budget", args->memory_budget,
                  "Device + host memory one group may use: bytes, or 512M, 8G, 1.5G")
      ->capture_default_str();
  cmd->add_option("--level", g.level, "Pyramid level the groups are matched at (memory estimate)")
      ->capture_default_str();
  cmd->add_option("--tile-size", g.tile_size,
                  "footprint: tile side, in median footprint shorter sides (tiles of at least "
                  "64 px and at most 100,000 of them)")
      ->capture_default_str();
  cmd->add_option("--tile-views", g.tile_views,
                  "footprint: images a tile's points should be seen in")
      ->capture_default_str();
  cmd->add_option("--min-image-num", g.min_image_num,
                  "Images a patch must be seen in (run's --min-image-num): groups are checked "
                  "for images with fewer overlapping views")
      ->capture_default_str();
  cmd->add_option("--json", args->json, "Also write the plan as JSON to this file");
  AddBlockFlags(cmd, &args->flags);
  cmd->callback([args] {
    // Everything the user typed is checked before the block is read.
    args->grouping.strategy = ParseGroupingStrategy(args->strategy);
    try {
      args->grouping.memory_budget = ParseByteSize(args->memory_budget);
    } catch (const Error& e) {
      throw Error(std::string("--memory-budget: ") + e.what());
    }
    if (const std::string problem = args->grouping.Problem(); !problem.empty())
      throw Error("plan: expected " + problem);
    const BlockReadOptions read = ReadOptionsOf(args->flags);
    // A JSON path in a missing folder fails here, before the block is read.
    if (!args->json.empty()) AtomicFile check(args->json);
    const Block block = ReadBlock(args->block, read);
    const GroupingPlan plan = PlanGroups(block, args->grouping);
    PrintPlan(block, plan, std::cout);
    if (!args->json.empty()) {
      WriteTextAtomically(args->json, PlanToJson(block, plan).dump(2) + "\n");
      std::cout << "plan written to " << args->json << "\n";
    }
  });
}

}  // namespace sapmvs::cli

#pragma once
// DIR/report.json of `sapmvs run`, and the JSON pieces the checkpoints share.
#include <filesystem>
#include <nlohmann/json.hpp>

#include "sapmvs/block.h"
#include "sapmvs/dense_run.h"
#include "sapmvs/grouping.h"
#include "sapmvs/matcher.h"

namespace sapmvs {

// Writes `j` (indented) to `path` atomically; throws Error naming the path.
void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& j);
// Every field of the options: what a checkpoint must agree on to be reused.
nlohmann::json MatcherOptionsJson(const MatcherOptions& m);
// Counts, per-stage wall/device times and kernel times of one or more groups.
nlohmann::json MatchStatsJson(const MatchStats& s);
// Writes options.out / "report.json" atomically.
void WriteRunReport(const RunOptions& options, const RunReport& report, const Block& block,
                    const GroupingPlan& plan);

}  // namespace sapmvs

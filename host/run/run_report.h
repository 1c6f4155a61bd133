#pragma once
// DIR/report.json of `sapmvs run`, and the JSON pieces the checkpoints share.
#include <filesystem>
#include <nlohmann/json.hpp>

#include "sapmvs/block/block.h"
#include "sapmvs/match/match_stats.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/run/run_options.h"
#include "sapmvs/run/run_result.h"

namespace sapmvs {

// Writes `j` (indented) to `path` atomically; throws Error naming the path.
void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& j);
// Counts, per-stage wall times and kernel launches of one or more groups, and
// the device times when `device_times` (measured only with --profile; absent
// otherwise, so that no one reads an unmeasured 0 as a time).
nlohmann::json MatchStatsJson(const MatchStats& s, bool device_times);
// The version of report.json's layout; raised when a field changes meaning
// or type.
constexpr int kRunReportVersion = 2;
// Writes options.out / "report.json" atomically.
void WriteRunReport(const RunOptions& options, const RunReport& report, const Block& block,
                    const GroupingPlan& plan);

}  // namespace sapmvs

#pragma once
// Checkpoints of a whole-block run in DIR/groups/: plan.json (the groups and
// the matcher options they were matched with), and per finished group
// group_NNN.ply (its filtered cloud) and group_NNN.json (status and stats,
// written after the cloud, so that it marks a complete group). A later run
// with the same plan resumes; one with another plan or other options is
// refused rather than mixing clouds matched differently.
#include <filesystem>
#include <optional>

#include "sapmvs/block/block.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/match/match_stats.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/run/run_result.h"

namespace sapmvs {

struct GroupCheckpoint {
  long points = 0;
  double seconds = 0;
  GroupMemoryUse memory;
};

// Removes what `sapmvs run` writes into `out` (cloud.ply, cloud.las, dsm.tif
// and its side-car, dsm.png, report.json, profile.csv/json) and its
// checkpoints in out/groups, by name: a user's other files there stay.
void RemoveRunOutputs(const std::filesystem::path& out);
// Removes what `sapmvs evaluate --run` put into `out` (evaluation.json, its
// plots in evaluation/): it judged a cloud that is about to be replaced.
void RemoveRunEvaluation(const std::filesystem::path& out);
// plan.json and group_NNN.ply/.json/.claim in `dir`, and nothing else.
void RemoveCheckpoints(const std::filesystem::path& dir);

class RunCheckpoints {
 public:
  // Creates `dir`; with `restart` removes the checkpoints an earlier run left
  // there (RemoveCheckpoints).
  // Throws Error naming plan.json when it records another plan or options.
  // `own_margin_gsd`: each group matched its own ground and this margin
  // (RunOptions::own_margin_gsd); none when every group matched all of it.
  RunCheckpoints(std::filesystem::path dir, const Block& block, const GroupingPlan& plan,
                 const MatcherOptions& matcher, bool restart,
                 std::optional<double> own_margin_gsd = std::nullopt);

  bool Done(int group) const;
  GroupCheckpoint Read(int group) const;
  // `device_times`: the stats hold measured kernel times (--profile).
  void Write(int group, const PointCloud& cloud, const GroupCheckpoint& done,
             const MatchStats& stats, bool device_times);
  std::filesystem::path CloudPath(int group) const;
  std::filesystem::path StatusPath(int group) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace sapmvs

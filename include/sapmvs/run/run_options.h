#pragma once
// What `sapmvs run` is asked to do (RunOptions), apart from the run
// (dense_run.h) so that its report and checkpoints can take it.
#include <filesystem>
#include <string>
#include <vector>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/ortho/ortho_options.h"
#include "sapmvs/plan/grouping_options.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/run/cloud_merge.h"
#include "sapmvs/util/option_spec.h"

namespace sapmvs {

inline void ParseOptionValue(const std::string& text, LasVersion* version) {
  *version = ParseLasVersion(text);
}

struct RunOptions {
  std::filesystem::path block;  // any format ReadBlock takes
  // How to read it (format, image folder, size check, ground height).
  BlockReadOptions read;
  std::filesystem::path out;  // output folder, created when missing
  // OpenCL device: index or name substring, or "reference" for the CPU
  // reference backend ("" = SAPMVS_DEVICE, else the default OpenCL device).
  // Under mpirun a comma list: rank r of a machine takes entry r mod n.
  std::string device;
  MatcherOptions matcher;
  // The plan is made for `matcher` (its level and min_image_num).
  GroupingOptions grouping;
  // Discard DIR/groups/ and start over instead of resuming.
  bool restart = false;
  // Match at most this many groups in this call, then stop (resumable);
  // 0 = all. For matching a long block over several calls.
  int max_groups = 0;
  // Each group of several matches only the ground it owns (GroundRegion:
  // nearer its centre than any other group's), widened by this many ground
  // sample distances of the level matched, so that neighbours overlap where
  // they meet. >= 0.
  double own_margin_gsd = 4.0;
  // Every group matches all the ground its images see, as the paper's
  // groups did; the merge then keeps one of each pair of near points.
  bool share_ground = false;
  // The merge levels the seams between groups (seam_leveling.h): a group's
  // heights meet its neighbour's at their border and fade back to its own
  // over this many ground sample distances of the level matched. 0 = off.
  double seam_feather_gsd = 20.0;
  // The merge keeps both groups' points within this many ground sample
  // distances of their border, so that the DSM's cells there hold both
  // surfaces and pass from one to the other. On Caliterra, with the seams
  // levelled, neighbouring DSM cells across a border differed by a median
  // 3.4 cm at 0, 2.6 at 1, 2.35 at 2 and 2.5 at 3 (2.3 inside a group), at
  // the same local noise. 0 = off.
  double seam_blend_gsd = 2.0;
  // Merge: a point is a duplicate of another group's point within this many
  // ground sample distances of the matched level. > 0.
  double merge_radius_gsd = 1.0;
  // Merge tile by tile, about this many group points a tile, so that the
  // merge, the DSM and the writers never hold the block's points at once;
  // a block with fewer is merged whole (tiled_merge.h). >= 1000.
  int merge_tile_points = 250000;
  DsmOptions dsm;
  OrthoOptions ortho;
  // cloud.las: LAS 1.2 by default, which every reader opens (las_io.h).
  LasVersion las_version = LasWriteOptions{}.version;
  // Profile the device queue (CL_QUEUE_PROFILING_ENABLE; the reference's
  // wall clock): kernel device times in the report, and the profile tables
  // (run_profile.h).
  bool profile = false;
  // Not an option: the command line that asked for the run, for report.json.
  std::vector<std::string> command_line;

  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
  bool Check() const;
};

// The run's own flags (option_spec.h); the matcher's, the grouping's and the
// DSM's are described beside their structs. `block` and `out` are arguments
// rather than tunables, and --profile also names a file: cli_run.cc adds
// those three.
template <class F>
void VisitFields(RunOptions& o, F&& f) {
  f(Field(o.device, "device")
        .Flag("--device")
        .In("Device")
        .Help("OpenCL device: index or name substring (see `sapmvs devices`), or "
              "`reference` for the CPU reference (no OpenCL); under mpirun a comma list, "
              "e.g. 0,1: the machine's rank r takes entry r mod n"));
  f(Field(o.restart, "restart")
        .Flag("--restart")
        .In("Output and resume")
        .Help("Discard the checkpoints in DIR/groups and start over"));
  f(Field(o.max_groups, "max_groups")
        .Flag("--max-groups")
        .In("Output and resume")
        .Unit("groups")
        .Range(AtLeast(0))
        .Help("Match at most this many groups now, then stop (resumable; 0 = all)"));
  f(Field(o.own_margin_gsd, "own_margin_gsd")
        .Flag("--own-margin")
        .In("Merge and DSM")
        .Unit("GSDs")
        .Range(AtLeast(0))
        .Help("Each group matches its own ground (nearer its centre than any other's) and "
              "this many GSDs beyond it"));
  f(Field(o.share_ground, "share_ground")
        .Flag("--share-ground")
        .In("Merge and DSM")
        .Help("Every group matches all the ground its images see (the merge drops the "
              "duplicates)"));
  f(Field(o.seam_feather_gsd, "seam_feather_gsd")
        .Flag("--seam-feather")
        .In("Merge and DSM")
        .Unit("GSDs")
        .Range(AtLeast(0))
        .Help("Merge: groups' heights meet at their borders and fade back over this many GSDs "
              "(0 = off)"));
  f(Field(o.seam_blend_gsd, "seam_blend_gsd")
        .Flag("--seam-blend")
        .In("Merge and DSM")
        .Unit("GSDs")
        .Range(AtLeast(0))
        .Help("Merge: both groups' points are kept within this many GSDs of their border "
              "(0 = off)"));
  f(Field(o.merge_radius_gsd, "merge_radius_gsd")
        .Flag("--merge-radius")
        .In("Merge and DSM")
        .Unit("GSDs")
        .Range(Above(0))
        .Help("Merge: duplicate distance, GSDs of the level matched"));
  f(Field(o.merge_tile_points, "merge_tile_points")
        .Flag("--merge-tile-points")
        .In("Merge and DSM")
        .Unit("points")
        .Range(AtLeast(1000))
        .Help("Merge: group points per tile (a block with fewer is merged whole)"));
  f(Field(o.las_version, "las_version")
        .Flag("--las-version")
        .In("Merge and DSM")
        .Help("cloud.las: 1.2 (format 2, every reader opens it) or 1.4 (format 7)"));
}

}  // namespace sapmvs

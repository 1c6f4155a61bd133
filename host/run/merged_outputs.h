#pragma once
// The end of a run: the group checkpoints merged tile by tile (tiled_merge.h)
// into cloud.ply, cloud.las, dsm.tif and its pictures, with the cloud's
// statistics, never holding the block's points at once. The merged points
// wait in a spill file (point_spill.h); the DSM takes them band by band
// (streamed_dsm.h); the writers stream them (ply_stream.h, WriteLasStream).
// A block that fits in one tile gives the bytes of the in-memory path.
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "sapmvs/io/las_io.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/run/run_result.h"
#include "sapmvs/run/tiled_merge.h"

namespace sapmvs {

struct MergedOutputsJob {
  std::vector<MergeSource> groups;
  MergeOptions merge;
  DsmOptions dsm;
  LasWriteOptions las;          // its crs is the block's
  std::string crs;              // for a cloud whose groups carry none
  std::filesystem::path out;    // the run folder
  std::filesystem::path block;  // named when no point survives
};

// Merges, measures and writes; fills report's merge, points, bounds,
// mean_spacing, dsm_cell, area, density and merge_tiles. Calls `end_stage`
// with "merge", "statistics" and "write" as each ends. Throws sapmvs::Error
// naming the block when no point survives; nothing is written then.
// Returns the DSM, for the orthophoto.
GeoRaster WriteMergedOutputs(const MergedOutputsJob& job, RunReport* report,
                             const std::function<void(const std::string&)>& end_stage);

}  // namespace sapmvs

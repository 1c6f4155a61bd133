#pragma once
// `sapmvs run`: a whole block. The images are planned into groups
// (grouping.h; one group when the block has at most max_images images), each
// group is matched (match_group.h) and checkpointed to DIR/groups/, and the group
// clouds are merged (cloud_merge.h) into
//   DIR/cloud.ply    binary, world coordinates in double, CRS in the header
//   DIR/cloud.las    LAS 1.2 or 1.4 with RGB, score, views and normals
//                    (cloud_las.h) and the block's CRS
//   DIR/dsm.tif      GeoTIFF DSM (cloud_dsm.h); its pictures (dsm_picture.h):
//                    DIR/dsm_color.tif (georeferenced), DIR/dsm.png + dsm.pgw
//   DIR/ortho.tif    the true orthophoto on the DSM (true_ortho.h), and
//                    DIR/ortho.png + ortho.pgw to look at
//   DIR/report.json  provenance (version, commit, command line, times,
//                    machine, device), CRS and bounds, points, groups,
//                    per-stage times, kernels, the paper's statistics
//                    (Tables 4, 6, 8); device times only with --profile
// A killed run resumes from its last finished group; the merge always reads
// the checkpoints back, so a resumed run writes the same cloud as one that
// was never interrupted.
#include <iosfwd>

#include "sapmvs/run/run_options.h"
#include "sapmvs/run/run_result.h"

namespace sapmvs {

// Throws Error for bad options or input, NoDeviceError without a device.
// Outputs are written atomically: a failed run leaves no partial file.
RunReport RunDense(const RunOptions& options);

// The summary printed after a run, in the form of the paper's Tables 4/6/8.
void PrintRunSummary(const RunReport& report, std::ostream& out);

}  // namespace sapmvs

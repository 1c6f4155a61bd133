#pragma once
// `sapmvs run`: a whole block. The images are planned into groups
// (grouping.h; one group when the block has at most max_images images), each
// group is matched (matcher.h) and checkpointed to DIR/groups/, and the group
// clouds are merged (cloud_merge.h) into
//   DIR/cloud.ply    binary, world coordinates in double, CRS in the header
//   DIR/cloud.las    LAS 1.2 or 1.4 with RGB, score, views and normals
//                    (cloud_las.h) and the block's CRS
//   DIR/dsm.tif      GeoTIFF DSM (cloud_dsm.h); its pictures (dsm_picture.h):
//                    DIR/dsm_color.tif (georeferenced), DIR/dsm.png + dsm.pgw
//   DIR/report.json  provenance (version, commit, command line, times,
//                    machine, device), CRS and bounds, points, groups,
//                    per-stage times, kernels, the paper's statistics
//                    (Tables 4, 6, 8); device times only with --profile
// A killed run resumes from its last finished group; the merge always reads
// the checkpoints back, so a resumed run writes the same cloud as one that
// was never interrupted.
#include <Eigen/Core>
#include <chrono>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "sapmvs/block_reader.h"
#include "sapmvs/cloud_dsm.h"
#include "sapmvs/cloud_merge.h"
#include "sapmvs/grouping.h"
#include "sapmvs/las_io.h"
#include "sapmvs/matcher.h"

namespace sapmvs {

struct RunOptions {
  std::filesystem::path block;  // any format ReadBlock takes
  // How to read it (format, image folder, size check, ground height).
  BlockReadOptions read;
  std::filesystem::path out;  // output folder, created when missing
  // OpenCL device: index or name substring, or "reference" for the CPU
  // reference backend ("" = SAPMVS_DEVICE, else the default OpenCL device).
  std::string device;
  MatcherOptions matcher;
  // Its level and min_image_num are taken from the matcher's (Grouping()).
  GroupingOptions grouping;
  // Discard DIR/groups/ and start over instead of resuming.
  bool restart = false;
  // Match at most this many groups in this call, then stop (resumable);
  // 0 = all. For splitting a long run into sessions.
  int max_groups = 0;
  // Merge: a point is a duplicate of another group's point within this many
  // ground sample distances of the matched level. > 0.
  double merge_radius_gsd = 1.0;
  DsmOptions dsm;
  // cloud.las: LAS 1.2 by default, which every reader opens (las_io.h).
  LasVersion las_version = LasWriteOptions{}.version;
  // Profile the device queue (CL_QUEUE_PROFILING_ENABLE; the reference's
  // wall clock): kernel device times in the report, and the profile tables
  // (run_profile.h).
  bool profile = false;
  // Not an option: the command line that asked for the run, for report.json.
  std::vector<std::string> command_line;

  // `grouping` with the matcher's level and min_image_num, as the plan uses it.
  GroupingOptions Grouping() const;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
  bool Check() const;
};

struct GroupRun {
  int index = 0;  // 0-based
  std::vector<std::string> images;
  long points = 0;
  double seconds = 0;
  bool resumed = false;  // read from a checkpoint of an earlier call
};

// The device a run used (an OpenCL device or the CPU reference), as
// report.json names it.
struct RunDevice {
  std::string name;      // CL_DEVICE_NAME, or "reference"
  std::string vendor;    // CL_DEVICE_VENDOR
  std::string platform;  // CL_PLATFORM_NAME and CL_PLATFORM_VERSION
  std::string type;      // "GPU", "CPU" or "other"
};

struct RunReport {
  std::filesystem::path out;
  std::string device;  // one line, as `sapmvs devices` describes it
  RunDevice device_info;
  std::chrono::system_clock::time_point start_time, end_time;
  std::string strategy;
  bool finished = false;  // false: stopped by max_groups, outputs not written
  int images = 0;
  std::vector<GroupRun> groups;
  std::vector<std::string> ungrouped;  // images the plan put in no group (grouping.h)
  MatchStats stats;                    // summed over the groups matched in this call
  MergeStats merge;
  long points = 0;
  double mean_spacing = 0;  // mean nearest-neighbour distance, CRS units
  double density = 0;       // points per CRS unit squared of covered ground
  double area = 0;
  double dsm_cell = 0;
  // The merged cloud's bounding box, world (CRS) coordinates.
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
  double total_seconds = 0;
  double peak_rss_bytes = 0;
  std::vector<std::pair<std::string, double>> stages;  // wall seconds, this call
};

// Throws Error for bad options or input, NoDeviceError without a device.
// Outputs are written atomically: a failed run leaves no partial file.
RunReport RunDense(const RunOptions& options);

// The summary printed after a run, in the form of the paper's Tables 4/6/8.
void PrintRunSummary(const RunReport& report, std::ostream& out);

// Seconds as h:min:s, as the paper's tables give run times.
std::string FormatHms(double seconds);

}  // namespace sapmvs

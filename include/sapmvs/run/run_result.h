#pragma once
// What a `sapmvs run` did (RunReport): groups, device, statistics, merge,
// times. The run fills it; report.json, the summary and the profile read it.
#include <Eigen/Core>
#include <chrono>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "sapmvs/match/match_stats.h"
#include "sapmvs/run/cloud_merge.h"

namespace sapmvs {

// Memory that matching one group took, measured, to set beside the plan's
// estimate (GroupMemory).
struct GroupMemoryUse {
  // The process's RSS before the group: libraries, the block, the device's
  // context and what earlier groups left to the allocator.
  double rss_before_bytes = 0;
  // The process's peak RSS while matching the group, and whether it is the
  // group's own: false where the system cannot reset the peak
  // (ResetPeakRss), so that it is the process's peak so far.
  double peak_rss_bytes = 0;
  bool peak_of_group = false;
  // The device's buffers at their peak (PatchKernels::PeakDeviceBytes); on a
  // CPU device they are also part of the RSS.
  double peak_device_bytes = 0;
};

struct GroupRun {
  int index = 0;  // 0-based
  std::vector<std::string> images;
  long points = 0;
  double seconds = 0;
  bool resumed = false;              // read from a checkpoint of an earlier call
  int rank = -1;                     // under mpirun, the rank that matched it in this call
  double memory_estimate_bytes = 0;  // the plan's (GroupMemory::Total)
  GroupMemoryUse memory;
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
  // Under mpirun: the processes and this one's rank. Only rank 0 merges,
  // writes the outputs and prints the summary.
  int ranks = 1;
  int rank = 0;
  int images = 0;
  std::vector<GroupRun> groups;
  std::vector<std::string> ungrouped;  // images the plan put in no group (grouping.h)
  MatchStats stats;                    // summed over the groups matched in this call
  MergeStats merge;
  int merge_tiles = 0;  // tiles the merge was cut into (tiled_merge.h)
  long points = 0;
  double mean_spacing = 0;  // mean nearest-neighbour distance, CRS units
  double density = 0;       // points per CRS unit squared of covered ground
  double area = 0;
  double dsm_cell = 0;
  // The orthophoto (0 cells when none was made): its cell, CRS units, its
  // size, the cells an image coloured, the images that did, and the objects
  // each taken whole from one image.
  double ortho_cell = 0;
  int ortho_width = 0, ortho_height = 0;
  long ortho_filled_cells = 0;
  int ortho_images = 0;
  int ortho_objects = 0;
  // The merged cloud's bounding box, world (CRS) coordinates.
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
  double total_seconds = 0;
  double peak_rss_bytes = 0;
  // The run's own stages in this call (plan, match, merge, statistics,
  // write): wall seconds, the process's CPU seconds over the same span, all
  // threads, so that a stage that keeps one core busy shows, and the peak
  // resident memory during the stage where it is known: where the stage
  // raised the process's high-water mark, and for the match stage its
  // largest group's; NaN where the stage stayed below an earlier peak.
  struct Stage {
    std::string name;
    double wall = 0;
    double cpu = 0;
    double peak_rss_bytes = 0;
  };
  std::vector<Stage> stages;
};

// Seconds as h:min:s, as the paper's tables give run times.
std::string FormatHms(double seconds);

}  // namespace sapmvs

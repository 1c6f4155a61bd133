#include "run/run_report.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>

#include "sapmvs/io/raster_io.h"
#include "sapmvs/match/ground_region.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/log.h"
#include "sapmvs/util/thread_count.h"
#include "util/build_info.h"
#include "util/machine_info.h"
#include "util/option_json.h"

namespace sapmvs {

std::string FormatHms(double seconds) {
  const long s = std::lround(std::max(0.0, seconds));
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
  return buf;
}

void WriteJsonFile(const std::filesystem::path& path, const nlohmann::json& j) {
  WriteStreamAtomically(path, [&](std::ostream& f) { f << std::setw(2) << j << "\n"; });
}

nlohmann::json MatchStatsJson(const MatchStats& s, bool device_times) {
  nlohmann::json j;
  j["images"] = s.images;
  j["features"] = s.features;
  j["seeds"] = {{"tried", s.seeds_tried}, {"accepted", s.seeds_accepted}};
  j["edges"] = {{"edge_pixels", s.edge_points}, {"matched", s.matched_edge_points}};
  j["propagation"] = {{"waves", s.waves},
                      {"candidates", s.candidates},
                      {"largest_wave", s.largest_wave},
                      {"patches", s.patches},
                      {"pmvs_pass_patches", s.pmvs_pass_patches}};
  nlohmann::json sizes = nlohmann::json::object();
  for (const auto& [size, count] : s.accepted_by_size) sizes[std::to_string(size)] = count;
  j["propagation"]["accepted_by_size"] = sizes;
  j["filter"] = {{"points_before", s.points_before_filter},
                 {"score_floor", s.score_floor},
                 {"pmvs_pass_score_floor", s.pmvs_pass_score_floor},
                 {"plane_tolerance", s.plane_tolerance},
                 {"removed_score", s.removed_score},
                 {"removed_visibility", s.removed_visibility},
                 {"removed_neighbourhood", s.removed_neighbourhood},
                 {"removed_clusters", s.removed_clusters},
                 {"removed_depth_range", s.removed_depth_range},
                 {"removed_unfitted", s.removed_unfitted},
                 {"points", s.points}};
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& [name, t] : s.stages) {
    nlohmann::json stage = {{"stage", name}, {"wall_seconds", t.wall}};
    if (device_times) stage["device_seconds"] = t.device;
    stage["cpu_seconds"] = t.cpu;
    if (t.ncc_evaluations > 0) stage["ncc_evaluations"] = t.ncc_evaluations;
    stages.push_back(stage);
  }
  j["stages"] = stages;
  nlohmann::json kernels = nlohmann::json::array();
  for (const auto& [name, t] : s.kernels) {
    nlohmann::json kernel = {{"kernel", name},
                             {"launches", t.launches},
                             {"items", t.items},
                             {"ncc_evaluations", t.ncc_evaluations}};
    if (device_times) kernel["device_seconds"] = t.seconds;
    kernels.push_back(kernel);
  }
  j["kernels"] = kernels;
  j["gsd_at_level"] = s.gsd;
  return j;
}

namespace {

nlohmann::json CrsJson(const std::string& crs) {
  if (crs.empty()) return nullptr;
  const CrsIdentity id = IdentifyCrs(crs);
  return {{"epsg", id.epsg > 0 ? nlohmann::json(id.epsg) : nlohmann::json(nullptr)},
          {"name", id.name},
          {"definition", crs}};
}

nlohmann::json MachineJson() {
  const MachineInfo m = DescribeMachine();
  return {{"hostname", m.hostname},
          {"cpu", m.cpu_model},
          {"cores", m.cores},
          {"memory_bytes", m.memory_bytes},
          {"threads", HostThreadCount()}};
}

nlohmann::json Xyz(const Eigen::Vector3d& v) { return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}}; }

}  // namespace

void WriteRunReport(const RunOptions& options, const RunReport& report, const Block& block,
                    const GroupingPlan& plan) {
  nlohmann::json j;
  j["report_version"] = kRunReportVersion;
  j["sapmvs"] = {{"version", BuildVersion()}, {"commit", BuildCommit()}};
  j["command_line"] = options.command_line;
  j["start_time"] = Iso8601Utc(report.start_time);
  j["end_time"] = Iso8601Utc(report.end_time);
  j["machine"] = MachineJson();
  j["block"] = options.block.string();
  j["mode"] = ToString(options.matcher.mode);
  j["level"] = options.matcher.level;
  j["device"] = {{"description", report.device},
                 {"name", report.device_info.name},
                 {"vendor", report.device_info.vendor},
                 {"platform", report.device_info.platform},
                 {"type", report.device_info.type}};
  j["crs"] = CrsJson(block.crs);
  j["bounds"] = {{"min", Xyz(report.bounds_min)}, {"max", Xyz(report.bounds_max)}};
  j["origin"] = {block.origin.x(), block.origin.y(), block.origin.z()};
  j["images"] = report.images;
  if (report.ranks > 1) j["mpi_ranks"] = report.ranks;
  j["points"] = report.points;
  j["total_seconds"] = report.total_seconds;
  j["total_hms"] = FormatHms(report.total_seconds);
  j["mean_point_spacing"] = report.mean_spacing;
  j["density_per_unit2"] = report.density;
  j["covered_area_unit2"] = report.area;
  j["dsm_cell"] = report.dsm_cell;
  if (report.ortho_cell > 0) {
    const long cells = static_cast<long>(report.ortho_width) * report.ortho_height;
    j["ortho"] = {{"cell", report.ortho_cell},
                  {"width", report.ortho_width},
                  {"height", report.ortho_height},
                  {"filled_share", cells > 0 ? double(report.ortho_filled_cells) / cells : 0.0},
                  {"images", report.ortho_images},
                  {"objects", report.ortho_objects}};
  }
  j["peak_rss_bytes"] = report.peak_rss_bytes;
  j["grouping"] = report.strategy;
  j["ungrouped"] = report.ungrouped;
  j["matcher"] = OptionsJson(options.matcher);
  // The ground each group's points were kept on: the merge gives each XY to
  // the group with the nearest centre, so the regions tile the cloud's box.
  std::vector<Eigen::Vector2d> centers;
  for (const ImageGroup& group : plan.groups)
    centers.push_back(group.center + block.origin.head<2>());
  nlohmann::json groups = nlohmann::json::array();
  for (size_t g = 0; g < report.groups.size(); ++g) {
    const GroupRun& r = report.groups[g];
    nlohmann::json e = {{"group", r.index + 1},        {"images", r.images},
                        {"points", r.points},          {"seconds", r.seconds},
                        {"hms", FormatHms(r.seconds)}, {"from_checkpoint", r.resumed}};
    if (report.ranks > 1 && r.rank >= 0) e["rank"] = r.rank;
    if (g < plan.groups.size()) {
      const Eigen::Vector2d c = plan.groups[g].center + block.origin.head<2>();
      e["center"] = {c.x(), c.y()};
      const GroundRegion region =
          centers.size() > 1 ? GroundRegion(centers, static_cast<int>(g), 0) : GroundRegion();
      nlohmann::json outline = nlohmann::json::array();
      for (const Eigen::Vector2d& p :
           region.Outline(report.bounds_min.head<2>(), report.bounds_max.head<2>())) {
        outline.push_back({p.x(), p.y()});
      }
      e["region"] = outline;
      e["memory_estimate_bytes"] = {{"device", plan.groups[g].memory.device_bytes},
                                    {"host", plan.groups[g].memory.host_bytes},
                                    {"total", plan.groups[g].memory.Total()}};
    }
    if (r.memory.peak_rss_bytes > 0) {
      e["memory_measured_bytes"] = {{"rss_before", r.memory.rss_before_bytes},
                                    {"peak_rss", r.memory.peak_rss_bytes},
                                    {"peak_is_group_own", r.memory.peak_of_group},
                                    {"device_peak", r.memory.peak_device_bytes}};
    }
    if (g < report.merge.kept_by_group.size()) {
      e["kept_after_merge"] = report.merge.kept_by_group[g];
      e["kept_in_core"] = report.merge.core_by_group[g];
    }
    groups.push_back(e);
  }
  j["groups"] = groups;
  j["merge"] = {{"input", report.merge.input},
                {"kept", report.merge.kept},
                {"cross_group_duplicates", report.merge.duplicates},
                {"band_outliers", report.merge.band_outliers},
                {"seams_levelled", report.merge.seam_pairs},
                {"seam_offset", report.merge.seam_offset},
                {"tiles", report.merge_tiles}};
  // Matching stages (summed over the groups matched in this call, with their
  // device time), then the run's own: plan, match (all groups), merge, ...
  nlohmann::json matching = MatchStatsJson(report.stats, options.profile);
  nlohmann::json stages = matching["stages"];
  for (const RunReport::Stage& t : report.stages) {
    stages.push_back(
        {{"stage", "run " + t.name},
         {"wall_seconds", t.wall},
         {"cpu_seconds", t.cpu},
         {"peak_rss_bytes", std::isfinite(t.peak_rss_bytes) ? nlohmann::json(t.peak_rss_bytes)
                                                            : nlohmann::json(nullptr)},
         {"hms", FormatHms(t.wall)}});
  }
  j["stages"] = stages;
  j["kernels"] = matching["kernels"];
  matching.erase("stages");
  matching.erase("kernels");
  j["matching"] = matching;
  WriteJsonFile(options.out / "report.json", j);
}

}  // namespace sapmvs

#include "sapmvs/dense_run.h"

#include <chrono>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cl_runtime.h"
#include "sapmvs/atomic_file.h"
#include "sapmvs/block_reader.h"
#include "sapmvs/error.h"
#include "sapmvs/ply_io.h"

namespace sapmvs {

bool RunOptions::Check() const {
  if (block.empty()) {
    std::cerr << "RunOptions: expected a block path\n";
    return false;
  }
  if (out.empty()) {
    std::cerr << "RunOptions: expected an output folder\n";
    return false;
  }
  return matcher.Check();
}

namespace {

nlohmann::json ReportJson(const RunOptions& options, const RunReport& report, const Block& block) {
  const MatchStats& s = report.stats;
  nlohmann::json j;
  j["block"] = options.block.string();
  j["mode"] = ToString(options.matcher.mode);
  j["level"] = options.matcher.level;
  j["device"] = report.device;
  j["images"] = s.images;
  j["points"] = s.points;
  j["gsd_at_level"] = s.gsd;
  j["crs"] = block.crs;
  j["origin"] = {block.origin.x(), block.origin.y(), block.origin.z()};
  j["total_seconds"] = report.total_seconds;
  j["features"] = s.features;
  j["seeds"] = {{"tried", s.seeds_tried}, {"accepted", s.seeds_accepted}};
  j["edges"] = {{"edge_pixels", s.edge_points}, {"matched", s.matched_edge_points}};
  j["propagation"] = {{"waves", s.waves},
                      {"candidates", s.candidates},
                      {"largest_wave", s.largest_wave},
                      {"patches", s.patches}};
  nlohmann::json sizes = nlohmann::json::object();
  for (const auto& [size, count] : s.accepted_by_size) sizes[std::to_string(size)] = count;
  j["propagation"]["accepted_by_size"] = sizes;
  j["filter"] = {{"points_before", s.points_before_filter},
                 {"removed_visibility", s.removed_visibility},
                 {"removed_neighbourhood", s.removed_neighbourhood},
                 {"removed_clusters", s.removed_clusters}};
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& [name, t] : s.stages) {
    stages.push_back({{"stage", name}, {"wall_seconds", t.wall}, {"device_seconds", t.device}});
  }
  j["stages"] = stages;
  nlohmann::json kernels = nlohmann::json::array();
  for (const auto& [name, t] : s.kernels) {
    kernels.push_back({{"kernel", name},
                       {"launches", t.launches},
                       {"items", t.items},
                       {"device_seconds", t.seconds}});
  }
  j["kernels"] = kernels;
  return j;
}

}  // namespace

RunReport RunDense(const RunOptions& options) {
  if (options.block.empty()) throw Error("run: expected a block path");
  if (options.out.empty()) throw Error("run: expected an output folder (--out)");
  const std::string problem = options.matcher.Problem();
  if (!problem.empty()) throw Error("run: expected " + problem);
  const auto start = std::chrono::steady_clock::now();
  const Block block = ReadBlock(options.block);
  DeviceOptions device_options;
  device_options.device = options.device;
  device_options.profile = true;
  ClContext context(device_options);
  std::error_code ec;
  std::filesystem::create_directories(options.out, ec);
  if (ec) throw Error(options.out.string() + ": cannot create the output folder: " + ec.message());

  MatchResult result = MatchGroup(block, {}, options.matcher, context);
  RunReport report;
  report.stats = std::move(result.stats);
  report.device = context.device().Describe();
  report.cloud_path = options.out / "cloud.ply";
  report.report_path = options.out / "report.json";
  if (result.cloud.points.empty()) {
    throw Error(options.block.string() +
                ": no point survived matching and filtering; nothing "
                "written (check the orientation, or lower --threshold)");
  }
  WritePly(report.cloud_path, result.cloud);
  report.total_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const nlohmann::json j = ReportJson(options, report, block);
  WriteFileAtomically(report.report_path, [&](const std::filesystem::path& tmp) {
    std::ofstream f(tmp);
    f << std::setw(2) << j << "\n";
    if (!f) throw Error(report.report_path.string() + ": write failed");
  });
  return report;
}

void PrintRunSummary(const RunReport& report, std::ostream& out) {
  const MatchStats& s = report.stats;
  out << "device        " << report.device << "\n";
  out << "images        " << s.images << "\n";
  out << "seeds         " << s.seeds_accepted << " of " << s.seeds_tried << " tried\n";
  out << "propagation   " << s.waves << " waves, " << s.candidates << " candidates, " << s.patches
      << " patches";
  if (!s.accepted_by_size.empty()) {
    out << " (";
    bool first = true;
    for (auto it = s.accepted_by_size.rbegin(); it != s.accepted_by_size.rend(); ++it) {
      out << (first ? "" : ", ") << it->first << "x" << it->first << ": " << it->second;
      first = false;
    }
    out << ")";
  }
  out << "\n";
  out << "filter        " << s.points_before_filter << " -> " << s.points << " points\n";
  out << std::fixed << std::setprecision(2);
  for (const auto& [name, t] : s.stages) {
    out << "time " << std::left << std::setw(12) << name << std::right << std::setw(8) << t.wall
        << " s wall" << (t.device > 0 ? ", " : "");
    if (t.device > 0) out << t.device << " s in kernels";
    out << "\n";
  }
  out << "total         " << report.total_seconds << " s\n";
  out << "cloud         " << report.cloud_path.string() << "\n";
  out << "report        " << report.report_path.string() << "\n";
  out.unsetf(std::ios::floatfield);
}

}  // namespace sapmvs

#include "run/run_checkpoint.h"

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "run/run_report.h"
#include "sapmvs/util/error.h"
#include "util/option_json.h"

namespace sapmvs {

namespace {

nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path.string(), 0, "cannot read");
  try {
    return nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path.string(), 0,
                     std::string("expected JSON written by sapmvs run (") + e.what() + ")");
  }
}

nlohmann::json PlanRecord(const Block& block, const GroupingPlan& plan,
                          const MatcherOptions& matcher, std::optional<double> own_margin_gsd) {
  nlohmann::json groups = nlohmann::json::array(), views = nlohmann::json::array();
  auto names = [&](const std::vector<int>& ids) {
    nlohmann::json n = nlohmann::json::array();
    for (const int i : ids) n.push_back(block.images[i].name);
    return n;
  };
  for (const ImageGroup& g : plan.groups) {
    groups.push_back(names(g.images));
    views.push_back(names(g.views));
  }
  nlohmann::json record = {{"groups", groups}, {"views", views}, {"matcher", OptionsJson(matcher)}};
  // Absent when every group matched all its ground, so that such a run's
  // plan.json reads as before.
  if (own_margin_gsd) record["own_margin_gsd"] = *own_margin_gsd;
  return record;
}

// group_NNN.ply or group_NNN.json, as CloudPath/StatusPath name them.
bool IsGroupCheckpointName(const std::string& name) {
  const size_t dot = name.rfind('.');
  if (name.rfind("group_", 0) != 0 || dot == std::string::npos || dot < 9) return false;
  const std::string digits = name.substr(6, dot - 6);
  const std::string ext = name.substr(dot);
  return digits.find_first_not_of("0123456789") == std::string::npos &&
         (ext == ".ply" || ext == ".json" || ext == ".claim");
}

}  // namespace

void RemoveCheckpoints(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::remove(dir / "plan.json", ec);
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (IsGroupCheckpointName(it->path().filename().string())) {
      std::error_code rm;
      std::filesystem::remove(it->path(), rm);
    }
  }
}

void RemoveRunOutputs(const std::filesystem::path& out) {
  std::error_code ec;
  for (const char* f :
       {"cloud.ply", "cloud.las", "dsm.tif", "dsm.tif.aux.xml", "dsm.png", "dsm.pgw",
        "dsm_color.tif", "dsm_color.tif.aux.xml", "ortho.tif", "ortho.tif.aux.xml", "ortho.png",
        "ortho.pgw", "report.json", "report.html", "profile.csv", "profile.json"}) {
    std::filesystem::remove(out / f, ec);
  }
  RemoveCheckpoints(out / "groups");
  RemoveRunEvaluation(out);
}

void RemoveRunEvaluation(const std::filesystem::path& out) {
  std::error_code ec;
  for (const char* f : {"evaluation.json", "evaluation/dz_histogram.png", "evaluation/dz_map.png",
                        "evaluation/pseudo_errors.png", "evaluation"}) {
    std::filesystem::remove(out / f, ec);  // the folder only when nothing else is in it
  }
}

RunCheckpoints::RunCheckpoints(std::filesystem::path dir, const Block& block,
                               const GroupingPlan& plan, const MatcherOptions& matcher,
                               bool restart, std::optional<double> own_margin_gsd)
    : dir_(std::move(dir)) {
  std::error_code ec;
  if (restart) RemoveCheckpoints(dir_);
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw Error(dir_.string() + ": cannot create the checkpoint folder: " + ec.message());
  const nlohmann::json record = PlanRecord(block, plan, matcher, own_margin_gsd);
  const std::filesystem::path plan_path = dir_ / "plan.json";
  if (std::filesystem::exists(plan_path)) {
    if (ReadJson(plan_path) != record) {
      throw Error(plan_path.string() +
                  ": holds a run with other groups or matcher options; expected the same plan "
                  "to resume (give --restart to discard it)");
    }
  } else {
    WriteJsonFile(plan_path, record);
  }
}

std::filesystem::path RunCheckpoints::CloudPath(int group) const {
  char name[32];
  std::snprintf(name, sizeof(name), "group_%03d.ply", group + 1);
  return dir_ / name;
}

std::filesystem::path RunCheckpoints::StatusPath(int group) const {
  char name[32];
  std::snprintf(name, sizeof(name), "group_%03d.json", group + 1);
  return dir_ / name;
}

bool RunCheckpoints::Done(int group) const {
  if (!std::filesystem::exists(StatusPath(group)) || !std::filesystem::exists(CloudPath(group))) {
    return false;
  }
  // A status left empty or cut (a full disk, before writes were checked)
  // marks no finished group: it is matched again, not the resume refused.
  try {
    return ReadJson(StatusPath(group)).value("status", "") == "done";
  } catch (const InputError&) {
    return false;
  }
}

GroupCheckpoint RunCheckpoints::Read(int group) const {
  const nlohmann::json j = ReadJson(StatusPath(group));
  GroupCheckpoint c;
  c.points = j.value("points", 0L);
  c.seconds = j.value("seconds", 0.0);
  // Checkpoints from before the measurement have none: zeros, as not measured.
  if (const auto m = j.find("memory"); m != j.end() && m->is_object()) {
    c.memory.rss_before_bytes = m->value("rss_before_bytes", 0.0);
    c.memory.peak_rss_bytes = m->value("peak_rss_bytes", 0.0);
    c.memory.peak_of_group = m->value("peak_of_group", false);
    c.memory.peak_device_bytes = m->value("peak_device_bytes", 0.0);
  }
  return c;
}

void RunCheckpoints::Write(int group, const PointCloud& cloud, const GroupCheckpoint& done,
                           const MatchStats& stats, bool device_times) {
  WritePly(CloudPath(group), cloud);
  nlohmann::json j = MatchStatsJson(stats, device_times);
  j["status"] = "done";
  j["group"] = group + 1;
  j["points"] = static_cast<long>(cloud.points.size());
  j["seconds"] = done.seconds;
  j["memory"] = {{"rss_before_bytes", done.memory.rss_before_bytes},
                 {"peak_rss_bytes", done.memory.peak_rss_bytes},
                 {"peak_of_group", done.memory.peak_of_group},
                 {"peak_device_bytes", done.memory.peak_device_bytes}};
  WriteJsonFile(StatusPath(group), j);
}

}  // namespace sapmvs

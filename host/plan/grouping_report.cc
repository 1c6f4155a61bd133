// How a plan is shown: the table `sapmvs plan` prints (like the paper's
// Table 3) and its JSON.
#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "plan/grouping_internal.h"
#include "sapmvs/plan/grouping.h"
#include "sapmvs/util/byte_size.h"

namespace sapmvs {

std::string Fixed(double v, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", precision, v);
  return buf;
}

namespace {

// "IMG_1~IMG_6" for a run of consecutive block images (either way), else
// every name.
std::string NamesColumn(const Block& block, const std::vector<int>& ids) {
  bool run = ids.size() >= 3;
  for (size_t k = 1; k < ids.size() && run; ++k)
    run = std::abs(ids[k] - ids[k - 1]) == 1 && (ids[k] - ids[k - 1]) == (ids[1] - ids[0]);
  if (run) return block.images[ids.front()].name + "~" + block.images[ids.back()].name;
  std::string s;
  for (const int i : ids) s += (s.empty() ? "" : " ") + block.images[i].name;
  return s;
}

// Where an image that joined a group went: "group 3" or "group 3 (view)",
// "" when in none.
std::string JoinedAs(const GroupingPlan& plan, int i) {
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    const ImageGroup& grp = plan.groups[g];
    if (std::find(grp.images.begin(), grp.images.end(), i) != grp.images.end())
      return "group " + std::to_string(g + 1);
    if (std::find(grp.views.begin(), grp.views.end(), i) != grp.views.end())
      return "group " + std::to_string(g + 1) + " (view)";
  }
  return "";
}

}  // namespace

void PrintPlan(const Block& block, const GroupingPlan& plan, std::ostream& out) {
  const GroupingOptions& o = plan.options;
  out << "block       " << block.source.string() << " (" << block.format << "), "
      << block.images.size() << " images\n";
  out << "strips      " << plan.strips.size() << ":";
  for (const auto& s : plan.strips) out << " " << s.size();
  out << " images";
  if (!plan.outliers.empty()) out << ", " << plan.outliers.size() << " outliers";
  out << "\n";
  for (const StripOutlier& outlier : plan.outliers) {
    const std::string joined = JoinedAs(plan, outlier.image);
    out << "outlier     " << block.images[outlier.image].name << " " << outlier.reason << "; "
        << (joined.empty() ? "in no group" : "joins " + joined) << "\n";
  }
  out << "strategy    " << ToString(plan.strategy) << ": at most " << o.max_images
      << " images per group, level " << plan.matcher.level << ", memory budget "
      << FormatBytes(o.memory_budget);
  if (plan.strategy == GroupingStrategy::kFootprint)
    out << ", tiles of " << Fixed(o.tile_size, 2) << " footprint, " << o.tile_views
        << " views, up to " << o.tile_extra_views << " view-only images";
  else
    out << ", up to " << o.strip_views << " view-only images of other strips";
  out << "\n";
  out << "groups      " << plan.groups.size();
  if (plan.single_group) out << " (single group: the block fits one, so it is not split)";
  out << "\n";

  std::vector<std::array<std::string, 9>> rows;
  rows.push_back({"group", "strip", "image numbers", "image names", "images", "views",
                  "centre X, Y", "device", "host"});
  double largest = 0;
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    const ImageGroup& grp = plan.groups[g];
    std::string numbers;
    for (const int i : grp.images) numbers += (numbers.empty() ? "" : " ") + std::to_string(i + 1);
    rows.push_back({std::to_string(g + 1), grp.strip < 0 ? "-" : std::to_string(grp.strip + 1),
                    numbers, NamesColumn(block, grp.images), std::to_string(grp.images.size()),
                    std::to_string(grp.views.size()),
                    Fixed(grp.center.x(), 1) + ", " + Fixed(grp.center.y(), 1),
                    FormatBytes(grp.memory.device_bytes), FormatBytes(grp.memory.host_bytes)});
    largest = std::max(largest, grp.memory.Total());
  }
  std::array<size_t, 9> width{};
  for (const auto& r : rows)
    for (size_t c = 0; c < r.size(); ++c) width[c] = std::max(width[c], r[c].size());
  // Numbers right-aligned, text left-aligned; the last column unpadded.
  const bool right[9] = {true, true, false, false, true, true, true, true, true};
  for (const auto& r : rows) {
    std::string line;
    for (size_t c = 0; c < r.size(); ++c) {
      const std::string pad(width[c] - r[c].size(), ' ');
      line += (c ? "  " : "") + (right[c] ? pad + r[c] : r[c] + (c + 1 < r.size() ? pad : ""));
    }
    out << line << "\n";
  }
  for (size_t g = 0; g < plan.groups.size(); ++g) {
    if (plan.groups[g].short_of_views.empty()) continue;
    out << "note        group " << g + 1 << ": image(s)";
    for (const int i : plan.groups[g].short_of_views) out << " " << block.images[i].name;
    out << " overlap fewer than " << plan.matcher.min_image_num - 1
        << " other images of the group and cannot be matched there\n";
  }
  if (!plan.ungrouped.empty()) {
    out << "ungrouped  ";
    for (const int i : plan.ungrouped) out << " " << (i + 1) << " " << block.images[i].name;
    out << "\n";
  }
  out << "largest     " << FormatBytes(largest) << " (host";
  if (plan.process_bytes > 0) out << " + the process's " << FormatBytes(plan.process_bytes);
  out << ") of " << FormatBytes(o.memory_budget) << "; centres in the local frame, origin "
      << Fixed(block.origin.x(), 3) << " " << Fixed(block.origin.y(), 3) << "\n";
}

nlohmann::json PlanToJson(const Block& block, const GroupingPlan& plan) {
  using nlohmann::json;
  const GroupingOptions& o = plan.options;
  auto names = [&](const std::vector<int>& ids) {
    json a = json::array();
    for (const int i : ids) a.push_back(block.images[i].name);
    return a;
  };
  json j;
  j["block"] = block.source.string();
  j["format"] = block.format;
  j["images"] = block.images.size();
  j["origin"] = {block.origin.x(), block.origin.y(), block.origin.z()};
  j["strategy"] = ToString(plan.strategy);
  j["single_group"] = plan.single_group;
  j["options"] = {{"max_images", o.max_images},   {"memory_budget", o.memory_budget},
                  {"level", plan.matcher.level},  {"tile_size", o.tile_size},
                  {"tile_views", o.tile_views},   {"tile_extra_views", o.tile_extra_views},
                  {"strip_views", o.strip_views}, {"min_image_num", plan.matcher.min_image_num}};
  j["strips"] = json::array();
  for (const auto& s : plan.strips) j["strips"].push_back({{"indices", s}, {"names", names(s)}});
  j["outliers"] = json::array();
  for (const StripOutlier& out : plan.outliers) {
    const std::string joined = JoinedAs(plan, out.image);
    j["outliers"].push_back({{"index", out.image},
                             {"name", block.images[out.image].name},
                             {"kind", ToString(out.kind)},
                             {"reason", out.reason},
                             {"joins", joined.empty() ? json(nullptr) : json(joined)}});
  }
  j["groups"] = json::array();
  for (const ImageGroup& g : plan.groups) {
    json jg = {{"indices", g.images},
               {"names", names(g.images)},
               {"views", {{"indices", g.views}, {"names", names(g.views)}}},
               {"strip", g.strip < 0 ? json(nullptr) : json(g.strip)},
               {"center", {g.center.x(), g.center.y()}},
               {"memory",
                {{"device_bytes", g.memory.device_bytes},
                 {"host_bytes", g.memory.host_bytes},
                 {"process_bytes", g.memory.process_bytes}}},
               {"short_of_views", names(g.short_of_views)}};
    if (plan.strategy == GroupingStrategy::kFootprint)
      jg["tile"] = {{"min", {g.tile_min.x(), g.tile_min.y()}},
                    {"max", {g.tile_max.x(), g.tile_max.y()}}};
    j["groups"].push_back(jg);
  }
  j["ungrouped"] = {{"indices", plan.ungrouped}, {"names", names(plan.ungrouped)}};
  return j;
}

}  // namespace sapmvs

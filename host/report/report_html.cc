#include "sapmvs/report/report_html.h"

#include <array>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "report/html_text.h"
#include "report/svg_chart.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/byte_size.h"
#include "sapmvs/util/error.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// Colours that stay apart for readers with the common colour-vision
// deficiencies (Okabe and Ito).
constexpr const char* kBlue = "#0072b2";
constexpr const char* kOrange = "#e69f00";
constexpr const char* kGreen = "#009e73";

constexpr const char* kStyle = R"(
body{font-family:system-ui,sans-serif;margin:0 auto;max-width:1120px;padding:0 16px 48px;color:#222}
h1{margin:24px 0 4px;font-size:26px}h2{margin-top:36px;border-bottom:1px solid #ccc;font-size:20px}
.sub{color:#555;margin:0 0 12px}nav a{margin-right:14px}
table{border-collapse:collapse;margin:8px 0;font-size:14px}
th,td{padding:3px 10px;border-bottom:1px solid #e4e4e4;text-align:right;vertical-align:top}
th{background:#f3f3f3}td.l,th.l{text-align:left}
table.kv th{text-align:left;background:none;font-weight:600}table.kv td{text-align:left}
figure{margin:12px 0}figcaption{color:#444;font-size:14px;margin-top:4px}
.map{position:relative;display:inline-block;max-width:100%}.map img{display:block;max-width:100%}
.map svg{position:absolute;left:0;top:0;width:100%;height:100%}
img.pic{max-width:100%;border:1px solid #ddd}.plots img{max-width:49%;vertical-align:top}
code{font-size:13px;word-break:break-all}.note{color:#555;font-size:14px}
)";

std::string MaybeBytes(double bytes) { return std::isfinite(bytes) ? FormatBytes(bytes) : "–"; }

std::string Cell(const std::string& text, bool left = false) {
  return left ? "<td class=\"l\">" + text + "</td>" : "<td>" + text + "</td>";
}

std::string Row(const std::string& key, const std::string& value) {
  return "<tr><th>" + HtmlEscape(key) + "</th><td>" + value + "</td></tr>";
}

double Num(const json& j, const char* key, double fallback = NAN) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : fallback;
}

std::string Str(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_string() ? it->get<std::string>() : std::string();
}

json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw Error(path.string() + ": cannot open it (expected a run's report)");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw Error(path.string() + ": not JSON (" + e.what() + ")");
  }
}

// A world file's six numbers (pixel width, two rotations, pixel height, the
// top-left pixel's centre), or none when the file is missing or malformed.
bool ReadWorldFile(const fs::path& path, std::array<double, 6>* w) {
  std::ifstream in(path);
  for (double& v : *w) {
    if (!(in >> v) || !std::isfinite(v)) return false;
  }
  return (*w)[0] != 0 && (*w)[3] != 0;
}

// The names in a JSON array of strings, comma-separated.
std::string Joined(const json& names) {
  std::string out;
  for (const json& n : names) out += (out.empty() ? "" : ", ") + n.get<std::string>();
  return out;
}

// The groups' ground over the DSM picture, in the picture's pixels.
std::string GroupOverlay(const json& groups, const std::array<double, 6>& w, const cv::Size& size) {
  std::string svg = "<svg viewBox=\"0 0 " + std::to_string(size.width) + " " +
                    std::to_string(size.height) +
                    "\" preserveAspectRatio=\"none\" font-family=\"sans-serif\">";
  auto px = [&](double x, double y) {
    // Top-left pixel's centre at (w[4], w[5]); north-up, no rotation.
    return std::array<double, 2>{(x - w[4]) / w[0] + 0.5, (y - w[5]) / w[3] + 0.5};
  };
  const double font = std::max(12.0, size.width / 60.0);
  for (const json& g : groups) {
    const auto it = g.find("region");
    if (it == g.end() || !it->is_array() || it->size() < 3) continue;
    std::string points;
    double cx = 0, cy = 0;
    for (const json& p : *it) {
      const auto q = px(p.at(0).get<double>(), p.at(1).get<double>());
      points += Decimal(q[0], 1) + "," + Decimal(q[1], 1) + " ";
      cx += q[0] / it->size();
      cy += q[1] / it->size();
    }
    const std::string number = std::to_string(g.value("group", 0));
    svg += "<polygon points=\"" + points +
           "\" fill=\"none\" stroke=\"#000\" stroke-opacity=\"0.6\" stroke-width=\"" +
           Decimal(font / 5, 1) + "\"/><polygon points=\"" + points +
           "\" fill=\"none\" stroke=\"#fff\" stroke-width=\"" + Decimal(font / 10, 1) +
           "\"><title>group " + number + "</title></polygon>";
    svg += "<text x=\"" + Decimal(cx, 1) + "\" y=\"" + Decimal(cy + font / 3, 1) +
           "\" text-anchor=\"middle\" font-size=\"" + Decimal(font, 1) +
           "\" font-weight=\"700\" fill=\"#fff\" stroke=\"#000\" stroke-width=\"" +
           Decimal(font / 8, 1) + "\" paint-order=\"stroke\">" + number + "</text>";
  }
  return svg + "</svg>";
}

std::string Summary(const json& r, const std::string& units) {
  std::string s = "<table class=\"kv\">";
  s += Row("Block", "<code>" + HtmlEscape(Str(r, "block")) + "</code>");
  s += Row("Images", GroupedInteger(Num(r, "images")));
  s += Row("Mode, level",
           HtmlEscape(Str(r, "mode")) + ", level " + GroupedInteger(Num(r, "level", 0)));
  const json crs = r.value("crs", json());
  s += Row("Coordinates", crs.is_object()
                              ? HtmlEscape(Str(crs, "name")) +
                                    (crs.value("epsg", json()).is_number()
                                         ? " (EPSG:" + std::to_string(crs["epsg"].get<int>()) + ")"
                                         : std::string())
                              : "a local frame without a CRS");
  s += Row("Points", GroupedInteger(Num(r, "points")));
  s += Row("Run time",
           HtmlEscape(Str(r, "total_hms")) + " (" + Decimal(Num(r, "total_seconds"), 1) + " s)");
  s += Row("Peak memory", MaybeBytes(Num(r, "peak_rss_bytes")));
  const json device = r.value("device", json::object());
  s += Row("Device", HtmlEscape(Str(device, "description")));
  s += Row("Units", HtmlEscape(units));
  return s + "</table>";
}

// The paper's Tables 4, 6 and 8: images, points, spacing, run time.
std::string Statistics(const json& r) {
  return "<table><tr><th>Number of images</th><th>Point amount</th><th>Average distance between "
         "points</th><th>Density (points per unit²)</th><th>Covered area (unit²)</th><th>Run "
         "time (h:min:s)</th></tr><tr>" +
         Cell(GroupedInteger(Num(r, "images"))) + Cell(GroupedInteger(Num(r, "points"))) +
         Cell(Decimal(Num(r, "mean_point_spacing"), 4)) +
         Cell(Decimal(Num(r, "density_per_unit2"), 1)) +
         Cell(GroupedInteger(Num(r, "covered_area_unit2"))) +
         Cell(HtmlEscape(Str(r, "total_hms"))) + "</tr></table>";
}

std::string Pictures(const json& r, const fs::path& dir) {
  std::string s;
  const fs::path dsm = dir / "dsm.png";
  if (fs::exists(dsm)) {
    std::array<double, 6> w{};
    // A picture that does not decode gets no groups over it; the page says
    // it does not decode.
    const cv::Size size = [&] {
      try {
        return ReadImageFileSize(dsm);
      } catch (const Error&) {
        return cv::Size();
      }
    }();
    const bool placed = ReadWorldFile(dir / "dsm.pgw", &w) && size.width > 0;
    s += "<figure><div class=\"map\"><img alt=\"DSM\" src=\"" + FileDataUri(dsm, "image/png") +
         "\">" + (placed ? GroupOverlay(r.value("groups", json::array()), w, size) : "") +
         "</div><figcaption>The DSM (cells of " + Decimal(Num(r, "dsm_cell"), 3) +
         "), hill-shaded" +
         (placed ? "; outlined, the ground whose points each group kept in the merge" : "") +
         ".</figcaption></figure>";
  }
  const fs::path ortho = dir / "ortho.png";
  if (fs::exists(ortho)) {
    const json o = r.value("ortho", json::object());
    s += "<figure><img class=\"pic\" alt=\"orthophoto\" src=\"" + FileDataUri(ortho, "image/png") +
         "\"><figcaption>The true orthophoto: " + GroupedInteger(Num(o, "width")) + " × " +
         GroupedInteger(Num(o, "height")) + " cells of " + Decimal(Num(o, "cell"), 3) + ", " +
         Decimal(100 * Num(o, "filled_share"), 1) + " % coloured, from " +
         GroupedInteger(Num(o, "images")) + " images; " + GroupedInteger(Num(o, "objects")) +
         " raised objects each taken whole from one image (ortho.tif is the full "
         "resolution).</figcaption></figure>";
  }
  return s.empty() ? "<p class=\"note\">No pictures: the run wrote no dsm.png.</p>" : s;
}

std::string Groups(const json& r) {
  const json groups = r.value("groups", json::array());
  if (groups.empty()) return "<p class=\"note\">No groups.</p>";
  std::string s =
      "<table><tr><th>Group</th><th>Images</th><th>Points matched</th><th>Kept after the "
      "merge</th><th>Seconds</th><th>Memory estimate</th><th>Measured peak</th><th "
      "class=\"l\">Images</th></tr>";
  BarChart time{" s", {}, {{"matching", kBlue, {}}}, 1};
  BarChart memory{" MiB", {}, {{"estimate", kOrange, {}}, {"measured peak", kBlue, {}}}, 0};
  for (const json& g : groups) {
    const json images = g.value("images", json::array());
    const double estimate = Num(g.value("memory_estimate_bytes", json::object()), "total");
    const double peak = Num(g.value("memory_measured_bytes", json::object()), "peak_rss");
    const std::string label = "group " + std::to_string(g.value("group", 0));
    s += "<tr>" + Cell(std::to_string(g.value("group", 0))) + Cell(std::to_string(images.size())) +
         Cell(GroupedInteger(Num(g, "points"))) + Cell(GroupedInteger(Num(g, "kept_after_merge"))) +
         Cell(Decimal(Num(g, "seconds"), 1)) + Cell(MaybeBytes(estimate)) + Cell(MaybeBytes(peak)) +
         Cell(HtmlEscape(Joined(images)), true) + "</tr>";
    time.labels.push_back(label);
    time.series[0].values.push_back(Num(g, "seconds"));
    memory.labels.push_back(label);
    memory.series[0].values.push_back(estimate / (1 << 20));
    memory.series[1].values.push_back(peak / (1 << 20));
  }
  s += "</table>";
  const json ungrouped = r.value("ungrouped", json::array());
  if (!ungrouped.empty()) {
    s += "<p class=\"note\">In no group: " + HtmlEscape(Joined(ungrouped)) + ".</p>";
  }
  s += "<h3>Time per group</h3>" + BarChartSvg(time);
  s += "<h3>Memory per group</h3><p class=\"note\">The plan's estimate, and the process's peak "
       "resident memory while the group was matched.</p>" +
       BarChartSvg(memory);
  return s;
}

std::string Stages(const json& r) {
  BarChart run{" s", {}, {{"wall", kBlue, {}}, {"CPU", kGreen, {}}}, 1};
  BarChart matching = run;
  BarChart memory{" MiB", {}, {{"peak", kOrange, {}}}, 0};
  std::string table =
      "<table><tr><th class=\"l\">Stage</th><th>Wall (s)</th><th>CPU (s)</th><th>CPU / "
      "wall</th></tr>";
  for (const json& stage : r.value("stages", json::array())) {
    std::string name = Str(stage, "stage");
    const double wall = Num(stage, "wall_seconds"), cpu = Num(stage, "cpu_seconds");
    const bool own = name.rfind("run ", 0) == 0;
    BarChart& chart = own ? run : matching;
    if (own) {
      name = name.substr(4);
      if (stage.contains("peak_rss_bytes")) {
        memory.labels.push_back(name);
        memory.series[0].values.push_back(Num(stage, "peak_rss_bytes") / (1 << 20));
      }
    }
    chart.labels.push_back(name);
    chart.series[0].values.push_back(wall);
    chart.series[1].values.push_back(cpu);
    table += "<tr>" + Cell(HtmlEscape(own ? name : "matching: " + name), true) +
             Cell(Decimal(wall, 2)) + Cell(Decimal(cpu, 2)) +
             Cell(wall > 0 ? Decimal(cpu / wall, 2) : "–") + "</tr>";
  }
  std::string s = "<h3>The run's stages</h3>" + BarChartSvg(run);
  if (!memory.labels.empty()) {
    s += "<h3>Peak memory per stage</h3><p class=\"note\">The process's peak resident memory "
         "while the stage ran (the match stage's is its largest group's); no bar where a stage "
         "stayed below an earlier stage's peak.</p>" +
         BarChartSvg(memory);
  }
  if (!matching.labels.empty()) {
    s += "<h3>Matching, summed over the groups matched in this call</h3>" + BarChartSvg(matching);
  }
  return s + table + "</table>";
}

std::string Merge(const json& r) {
  const json m = r.value("merge", json::object());
  const double input = Num(m, "input"), duplicates = Num(m, "cross_group_duplicates");
  return "<table class=\"kv\">" + Row("Points from the groups", GroupedInteger(input)) +
         Row("Kept", GroupedInteger(Num(m, "kept"))) +
         Row("Cross-group duplicates dropped",
             GroupedInteger(duplicates) +
                 (input > 0 ? " (" + Decimal(100 * duplicates / input, 1) + " %)" : "")) +
         Row("Off the surface by a border, dropped", GroupedInteger(Num(m, "band_outliers"))) +
         Row("Seams levelled", GroupedInteger(Num(m, "seams_levelled"))) +
         Row("Median seam offset", Decimal(Num(m, "seam_offset"), 3)) + "</table>";
}

// The paper's Tables 9-11, and the plots `evaluate --run` wrote.
std::string Evaluation(const fs::path& dir) {
  const json e = ReadJson(dir / "evaluation.json");
  const json ref = e.value("reference", json::object());
  std::string s = "<p>Against <code>" + HtmlEscape(Str(ref, "path")) + "</code> (" +
                  HtmlEscape(Str(ref, "kind") == "dsm" ? "a DSM" : "LiDAR points") +
                  "), the cloud <code>" +
                  HtmlEscape(Str(e.value("cloud", json::object()), "path")) + "</code>.</p>";
  s += "<table><tr><th class=\"l\">Points</th><th>Checkpoint amount</th><th>RMSE</th><th>Max</th>"
       "<th>Mean</th><th>Median |dz|</th><th>Within " +
       Decimal(Num(e, "tolerance"), 2) + "</th></tr>";
  for (const json& row : e.value("rows", json::array())) {
    const double t = Num(row, "threshold");
    s += "<tr>" + Cell(std::isfinite(t) ? "|dz| ≤ " + Decimal(t, 2) : "all", true) +
         Cell(GroupedInteger(Num(row, "checkpoints"))) + Cell(Decimal(Num(row, "rmse"), 3)) +
         Cell(Decimal(Num(row, "max_abs"), 3)) + Cell(Decimal(Num(row, "mean"), 3)) +
         Cell(Decimal(Num(row, "median_abs"), 3)) +
         Cell(Decimal(100 * Num(row, "within_tolerance"), 1) + " %") + "</tr>";
  }
  s += "</table>";
  if (const auto c = e.find("completeness"); c != e.end() && c->is_object()) {
    s += "<p>Completeness: " + Decimal(100 * Num(*c, "share"), 1) + " % of " +
         GroupedInteger(Num(*c, "cells")) + " reference cells hold a point.</p>";
  }
  std::string plots;
  for (const char* name : {"dz_histogram.png", "dz_map.png", "pseudo_errors.png"}) {
    const fs::path p = dir / "evaluation" / name;
    if (fs::exists(p)) {
      plots +=
          "<img alt=\"" + std::string(name) + "\" src=\"" + FileDataUri(p, "image/png") + "\">";
    }
  }
  return s + (plots.empty() ? "" : "<div class=\"plots\">" + plots + "</div>");
}

std::string RunDetails(const json& r) {
  const json sapmvs = r.value("sapmvs", json::object());
  const json machine = r.value("machine", json::object());
  std::string s = "<table class=\"kv\">";
  std::string command;
  for (const json& arg : r.value("command_line", json::array())) {
    const std::string a = arg.is_string() ? arg.get<std::string>() : arg.dump();
    const bool plain = !a.empty() && a.find_first_of(" \t'\"\\$`;&|<>*?()") == std::string::npos;
    command += (command.empty() ? "" : " ") + (plain ? a : "'" + a + "'");
  }
  s += Row("Command", "<code>" + HtmlEscape(command) + "</code>");
  s += Row("Started, ended", HtmlEscape(Str(r, "start_time") + ", " + Str(r, "end_time")));
  s += Row("sapmvs", HtmlEscape(Str(sapmvs, "version") + " (" + Str(sapmvs, "commit") + ")"));
  s += Row("Machine", HtmlEscape(Str(machine, "hostname") + ": " + Str(machine, "cpu")) + ", " +
                          GroupedInteger(Num(machine, "cores")) + " cores, " +
                          MaybeBytes(Num(machine, "memory_bytes")));
  s += Row("Grouping", HtmlEscape(Str(r, "grouping")));
  s += "</table><details><summary>Matcher options</summary><pre>" +
       HtmlEscape(r.value("matcher", json::object()).dump(2)) + "</pre></details>";
  return s;
}

// Marks each picture the browser could not decode with a line of text, and
// the body with how many it decoded: a broken picture is said, not hidden.
constexpr const char* kScript = R"(<script>
addEventListener('load', () => {
  const pictures = Array.from(document.images);
  let decoded = 0;
  for (const p of pictures) {
    if (p.complete && p.naturalWidth > 0) { decoded++; continue; }
    const note = document.createElement('p');
    note.className = 'note';
    note.textContent = '(' + p.alt + ': the picture could not be decoded)';
    p.replaceWith(note);
  }
  document.body.dataset.picturesDecoded = decoded + '/' + pictures.length;
});
</script>)";

}  // namespace

fs::path WriteReportHtml(const fs::path& run_dir) {
  const fs::path report_path = run_dir / "report.json";
  const json r = ReadJson(report_path);
  if (!r.is_object() || !r.contains("report_version") || !r.contains("groups")) {
    throw Error(report_path.string() + ": not a report of `sapmvs run` (no report_version)");
  }
  const bool evaluated = fs::exists(run_dir / "evaluation.json");
  const std::string units = r.value("crs", json()).is_object()
                                ? "lengths in the units of the CRS"
                                : "lengths in the units of the block's frame";
  // A block file's folder names the block better than block.yaml does.
  const fs::path block = fs::path(Str(r, "block")).lexically_normal();
  const std::string title =
      "sapmvs run: " +
      (block.has_extension() ? block.parent_path().filename() / block.filename() : block.filename())
          .string();
  std::string page =
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
      "<meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">"
      "<title>" +
      HtmlEscape(title) + "</title><style>" + kStyle + "</style></head><body>\n";
  page += "<h1>" + HtmlEscape(title) + "</h1><p class=\"sub\">" + HtmlEscape(Str(r, "end_time")) +
          " · " + GroupedInteger(Num(r, "points")) + " points in " +
          HtmlEscape(Str(r, "total_hms")) + "</p>";
  page +=
      "<nav><a href=\"#summary\">Summary</a><a href=\"#pictures\">DSM and orthophoto</a>"
      "<a href=\"#groups\">Groups</a><a href=\"#stages\">Time</a><a "
      "href=\"#merge\">Merge</a>" +
      std::string(evaluated ? "<a href=\"#evaluation\">Evaluation</a>" : "") +
      "<a href=\"#run\">The run</a></nav>\n";
  page += "<h2 id=\"summary\">Summary</h2>" + Summary(r, units);
  page += "<h3>Statistics (the paper's Tables 4, 6 and 8)</h3>" + Statistics(r);
  page += "\n<h2 id=\"pictures\">DSM and orthophoto</h2>" + Pictures(r, run_dir);
  page += "\n<h2 id=\"groups\">Groups</h2>" + Groups(r);
  page += "\n<h2 id=\"stages\">Time per stage</h2>" + Stages(r);
  page += "\n<h2 id=\"merge\">Merge</h2>" + Merge(r);
  if (evaluated) {
    page +=
        "\n<h2 id=\"evaluation\">Evaluation (the paper's Tables 9-11)</h2>" + Evaluation(run_dir);
  }
  page += "\n<h2 id=\"run\">The run</h2>" + RunDetails(r);
  page += kScript;
  page += "\n</body></html>\n";
  const fs::path out = run_dir / "report.html";
  WriteStreamAtomically(out, [&](std::ostream& f) { f << page; });
  return out;
}

}  // namespace sapmvs

// End-to-end benchmark: whole `sapmvs run`s of simulated presets in both
// modes, in one run, so that the SAPMVS/PMVS ratios compare like with like on
// a shared, noisy machine. Per preset and mode: wall time, points, points/s,
// kernel share of the time, and accuracy against the simulator's exact
// surface (share within 1 GSD, median |dz|, coverage). Writes a CSV and a
// PNG chart (time and points per preset, both modes). Each run's profile
// (sapmvs run --profile) lands in WORK/run_PRESET_MODE/profile.{csv,json,txt}.
//
//   end_to_end [--presets small,campus,city] [--modes sapmvs,pmvs] [--work /tmp/sapmvs_e2e]
//              [--csv profiling/results/end_to_end.csv]
//              [--chart profiling/results/end_to_end.png]
//              [matcher and grouping flags of `sapmvs run`]
#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "run/run_profile.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/evaluate/surface_check.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/plan/grouping_options.h"
#include "sapmvs/run/dense_run.h"
#include "sapmvs/simulate/simulate.h"
#include "sapmvs/util/error.h"
#include "truth_check.h"
#include "util/option_flags.h"

using namespace sapmvs;
namespace fs = std::filesystem;

namespace {

struct Row {
  std::string preset, mode;
  int images = 0, groups = 0;
  double seconds = 0, kernel_seconds = 0;
  long points = 0;
  SurfaceCheck check;
};

void DrawChart(const std::vector<Row>& rows, const std::vector<std::string>& presets,
               const fs::path& path) {
  const int panel_w = 520, panel_h = 360, margin = 60;
  cv::Mat img(panel_h + 2 * margin, 2 * panel_w + 3 * margin, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar colours[2] = {cv::Scalar(180, 119, 31),
                                 cv::Scalar(14, 127, 255)};  // sapmvs, pmvs
  const char* modes[2] = {"sapmvs", "pmvs"};
  for (int panel = 0; panel < 2; ++panel) {
    const int x0 = margin + panel * (panel_w + margin), y0 = margin;
    double top = 0;
    for (const Row& r : rows) top = std::max(top, panel == 0 ? r.seconds : r.points / 1e3);
    if (!(top > 0)) top = 1;
    cv::rectangle(img, {x0, y0}, {x0 + panel_w, y0 + panel_h}, cv::Scalar(200, 200, 200));
    cv::putText(img, panel == 0 ? "wall time, s" : "points, thousands", {x0, y0 - 20},
                cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    const int slot = panel_w / std::max<size_t>(1, presets.size());
    for (size_t p = 0; p < presets.size(); ++p) {
      for (int m = 0; m < 2; ++m) {
        for (const Row& r : rows) {
          if (r.preset != presets[p] || r.mode != modes[m]) continue;
          const double v = panel == 0 ? r.seconds : r.points / 1e3;
          const int h = static_cast<int>((panel_h - 30) * v / top);
          const int bx = x0 + static_cast<int>(p) * slot + slot / 6 + m * slot / 3;
          cv::rectangle(img, {bx, y0 + panel_h - h}, {bx + slot / 3 - 4, y0 + panel_h}, colours[m],
                        cv::FILLED);
          std::ostringstream label;
          label << std::fixed << std::setprecision(v < 10 ? 1 : 0) << v;
          cv::putText(img, label.str(), {bx, y0 + panel_h - h - 5}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                      cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
        }
      }
      cv::putText(img, presets[p], {x0 + static_cast<int>(p) * slot + slot / 3, y0 + panel_h + 20},
                  cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    }
  }
  for (int m = 0; m < 2; ++m) {
    const int lx = margin + m * 120, ly = panel_h + 2 * margin - 15;
    cv::rectangle(img, {lx, ly - 10}, {lx + 12, ly}, colours[m], cv::FILLED);
    cv::putText(img, modes[m], {lx + 18, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
  }
  if (!cv::imwrite(path.string(), img)) throw Error(path.string() + ": cannot write the chart");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("End-to-end benchmark: whole runs of presets in both modes");
  std::vector<std::string> presets = {"small", "campus", "city"};
  std::vector<std::string> modes = {"sapmvs", "pmvs"};
  std::string work = "/tmp/sapmvs_e2e", csv_path = "profiling/results/end_to_end.csv";
  std::string chart_path = "profiling/results/end_to_end.png", device;
  MatcherOptions base;
  app.add_option("--presets", presets, "Simulator presets")->delimiter(',')->capture_default_str();
  app.add_option("--modes", modes,
                 "Modes to run (one alone for an ablation: its ratios then print nothing)")
      ->delimiter(',')
      ->check(CLI::IsMember({"sapmvs", "pmvs"}))
      ->capture_default_str();
  app.add_option("--work", work, "Folder for the simulated blocks and runs")->capture_default_str();
  app.add_option("--csv", csv_path, "CSV to write")->capture_default_str();
  app.add_option("--chart", chart_path, "PNG chart to write")->capture_default_str();
  app.add_option("--device", device, "OpenCL device");
  // Every matcher flag of `sapmvs run` but --mode (both modes run here).
  cli::AddOptionFlags(&app, &base, cli::CompareModesMatcherFields());
  GroupingOptions grouping;
  cli::AddOptionFlags(&app, &grouping);
  CLI11_PARSE(app, argc, argv);
  try {
    if (const std::string problem = base.Problem(); !problem.empty())
      throw Error("expected " + problem);
    if (const std::string problem = grouping.Problem(); !problem.empty())
      throw Error("expected " + problem);
    const int level = base.level;
    std::vector<Row> rows;
    for (const std::string& preset : presets) {
      const fs::path sim = fs::path(work) / preset;
      if (!fs::exists(sim / "block.yaml")) {
        std::cerr << "simulating " << preset << " into " << sim << "\n";
        SimulateOptions so;
        so.preset = preset;
        so.out = sim;
        so.quiet = true;
        Simulate(so);
      }
      const Block block = ReadBlock(sim / "block.yaml");
      const Truth truth = ReadTruth(sim / "truth" / "dsm.tif");
      const double gsd = EstimateBlockGeometry(block).gsd_median;
      for (const std::string& mode : modes) {
        std::cerr << preset << " " << mode << "...\n";
        RunOptions o;
        o.block = sim / "block.yaml";
        o.out = fs::path(work) / ("run_" + preset + "_" + mode);
        o.device = device;
        o.restart = true;
        o.profile = true;
        o.matcher = base;
        o.grouping = grouping;
        o.matcher.mode = ParseMatchMode(mode);
        o.matcher.progress = false;
        const RunReport report = RunDense(o);
        WriteProfile(report, o.out / "profile.csv");  // and profile.json
        std::ofstream tables(o.out / "profile.txt");
        PrintProfile(report, tables);
        Row row;
        row.preset = preset;
        row.mode = mode;
        row.images = report.images;
        row.groups = static_cast<int>(report.groups.size());
        row.seconds = report.total_seconds;
        for (const auto& [name, k] : report.stats.kernels) row.kernel_seconds += k.seconds;
        row.points = report.points;
        row.check = CheckAgainstTruth(ReadPly(o.out / "cloud.ply"), truth, block, gsd, level);
        rows.push_back(row);
      }
    }
    std::ofstream csv(csv_path);
    csv << "preset,mode,images,groups,wall_s,kernel_s,points,points_per_s,within_1gsd,"
           "median_abs_dz,coverage\n";
    std::cout << "preset   mode    images groups   wall s  kernel%    points  points/s  <=1 GSD  "
                 "median|dz|  coverage\n";
    for (const Row& r : rows) {
      csv << r.preset << "," << r.mode << "," << r.images << "," << r.groups << "," << r.seconds
          << "," << r.kernel_seconds << "," << r.points << "," << r.points / r.seconds << ","
          << r.check.share_within << "," << r.check.median_abs_dz << "," << r.check.coverage
          << "\n";
      std::cout << std::left << std::setw(9) << r.preset << std::setw(8) << r.mode << std::right
                << std::setw(6) << r.images << std::setw(7) << r.groups << std::fixed
                << std::setprecision(1) << std::setw(9) << r.seconds << std::setw(8)
                << 100 * r.kernel_seconds / r.seconds << "%" << std::setw(10) << r.points
                << std::setw(10) << std::setprecision(0) << r.points / r.seconds
                << std::setprecision(1) << std::setw(8) << 100 * r.check.share_within << "%"
                << std::setprecision(3) << std::setw(12) << r.check.median_abs_dz
                << std::setprecision(1) << std::setw(9) << 100 * r.check.coverage << "%\n";
      std::cout.unsetf(std::ios::floatfield);
    }
    std::cout << "\nSAPMVS/PMVS   speed   points\n";
    for (const std::string& preset : presets) {
      const Row *s = nullptr, *p = nullptr;
      for (const Row& r : rows) {
        if (r.preset == preset) (r.mode == "sapmvs" ? s : p) = &r;
      }
      if (s && p) {
        std::cout << std::left << std::setw(12) << preset << std::right << std::fixed
                  << std::setprecision(2) << std::setw(7) << p->seconds / s->seconds << "x"
                  << std::setw(8) << static_cast<double>(s->points) / p->points << "x\n";
      }
    }
    csv.close();
    if (!csv) throw Error(csv_path + ": write failed");
    DrawChart(rows, presets, chart_path);
    std::cout << "wrote " << csv_path << " and " << chart_path << "\n";
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 1;
  }
  return 0;
}

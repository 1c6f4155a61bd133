// `sapmvs evaluate CLOUD --reference FILE`: height accuracy against LiDAR or a
// DSM, laid out like the paper's Tables 9-11.

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "cli/cli.h"
#include "sapmvs/evaluate/evaluate.h"
#include "sapmvs/report/report_html.h"

namespace sapmvs::cli {

void RegisterEvaluateCommand(CLI::App& app, const GlobalFlags& global) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate", "Height accuracy of a dense cloud against LiDAR or a DSM (RMSE, max, % within)");
  cmd->add_option("cloud", o->cloud, "Dense cloud: .ply, .las, or .xyz/.txt")->required();
  cmd->add_option("--reference", o->reference,
                  "LiDAR points (.las, .xyz, .txt, .ply) or a DSM raster (.tif, .tiff, .vrt)")
      ->required();
  cmd->add_option("--radius", o->radius,
                  "LiDAR: XY search radius d, CRS units (default: 2 x the LiDAR's median "
                  "nearest-neighbour spacing; at most 50 x)");
  cmd->add_option("--tolerance", o->tolerance,
                  "|dz| counted as within tolerance, CRS units (the paper's 1 m; use block "
                  "units for a block without a metric frame)")
      ->capture_default_str();
  cmd->add_option("--drop-above", o->drop_above,
                  "Pseudo-error thresholds T1,T2,...: one more row each, without |dz| > T")
      ->delimiter(',')
      ->allow_extra_args(false);
  cmd->add_option("--footprint", o->footprint,
                  "DSM: footprint for completeness, xmin,ymin,xmax,ymax (CRS units; write "
                  "--footprint=... when xmin is negative)")
      ->delimiter(',')
      ->allow_extra_args(false);
  cmd->add_option("--block", o->block,
                  "DSM: footprint for completeness = cells seen by at least 2 images of BLOCK");
  cmd->add_option("--json", o->json, "Write the report as JSON to FILE");
  cmd->add_option("--plots", o->plots,
                  "Write dz_histogram.png, dz_map.png, pseudo_errors.png into DIR");
  cmd->add_option("--run", o->run,
                  "A run folder: write evaluation.json and the plots (evaluation/) into it "
                  "and add them to its report.html");
  cmd->callback([o, &global] {
    o->quiet = global.quiet;
    const EvaluationReport report = Evaluate(*o);
    PrintEvaluationTable(report, std::cout);
    if (!o->json.empty()) {
      WriteEvaluationJson(report, o->json);
      std::cout << "json          " << o->json.string() << "\n";
    }
    if (!o->plots.empty()) {
      for (const auto& p : WriteEvaluationPlots(report, o->plots)) {
        std::cout << "plot          " << p.string() << "\n";
      }
    }
    if (!o->run.empty()) {
      WriteEvaluationJson(report, o->run / "evaluation.json");
      WriteEvaluationPlots(report, o->run / "evaluation");
      const std::filesystem::path html = WriteReportHtml(o->run);
      std::cout << "report        " << html.string() << "\n";
    }
  });
}

}  // namespace sapmvs::cli

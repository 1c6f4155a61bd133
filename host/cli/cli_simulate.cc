// `sapmvs simulate --preset NAME --out DIR`: a synthetic block with exact truth.

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>

#include "cli/cli.h"
#include "sapmvs/simulate/simulate.h"

namespace sapmvs::cli {

void RegisterSimulateCommand(CLI::App& app, const GlobalFlags& global) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate", "Render a synthetic block with exact truth: block.yaml, images, DSM, LiDAR");
  std::string presets;
  for (const std::string& p : SimulatePresetNames()) presets += (presets.empty() ? "" : ", ") + p;
  cmd->add_option("--preset", o->preset, "Preset: " + presets)->capture_default_str();
  cmd->add_option("--out", o->out, "Output folder (created)")->required();
  cmd->add_option("--seed", o->seed, "Random seed; the same seed gives the same bytes")
      ->capture_default_str();
  cmd->add_option("--scale", o->scale, "Image resolution factor (0.5 halves width and height)")
      ->capture_default_str();
  cmd->add_option("--angles", o->angles,
                  "Angle order written to block.yaml: omega-phi-kappa or phi-omega-kappa (default: "
                  "the preset's)");
  cmd->add_option("--units", o->units,
                  "Angle unit written to block.yaml: deg, gon or rad (default: the preset's)");
  cmd->add_flag("--cross-strip", o->cross_strip, "Add one strip flown across the others");
  cmd->add_option("--overlap", o->overlap,
                  "Forward and side overlap FWD,SIDE in percent of the footprint at the mean "
                  "ground, e.g. 88,30 (default: the preset's)")
      ->delimiter(',')
      ->allow_extra_args(false);
  cmd->add_option("--strips", o->strips,
                  "Strips to fly, all of --strip-images (default: the preset's)");
  cmd->add_option("--strip-images", o->strip_images,
                  "Images per strip (default: the preset's longest strip)");
  cmd->add_option("--exposure", o->exposure,
                  "Largest relative exposure change between images (default: the preset's)");
  cmd->add_option("--supersampling", o->supersampling,
                  "Rays per pixel side (2 = 2x2; 1 aliases, for timing runs of large images)")
      ->capture_default_str();
  cmd->add_option("--noise", o->noise, "Sensor noise, grey levels (1 sigma)")
      ->capture_default_str();
  cmd->add_flag("--xyz", o->xyz, "Also write truth/lidar.xyz");
  auto no_ortho = std::make_shared<bool>(false);
  cmd->add_flag("--no-truth-ortho", *no_ortho, "Do not write truth/ortho.tif");
  cmd->callback([o, no_ortho, &global] {
    o->quiet = global.quiet;
    o->ortho = !*no_ortho;
    const SimulateSummary s = Simulate(*o);
    std::cout << "simulated " << s.images << " images of " << s.width << "x" << s.height
              << " px in " << s.strips << " strips, GSD " << s.gsd << " m at " << s.flying_height
              << " m, " << 100 * s.forward_overlap << " % forward and " << 100 * s.side_overlap
              << " % side overlap (base " << s.base << " m, " << s.neighbour_angle
              << " deg between neighbours), " << s.lidar_points << " LiDAR points, angles "
              << ToString(s.order) << " in " << ToString(s.unit) << "\n"
              << "block: " << (o->out / "block.yaml").string() << "\n";
  });
}

}  // namespace sapmvs::cli

#include "simulate/sim_presets.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "sapmvs/util/error.h"

namespace sapmvs::sim {

const std::vector<Preset>& AllPresets() {
  static const std::vector<Preset> presets = [] {
    std::vector<Preset> p;
    {
      Preset t;
      t.name = "tiny";
      t.description = "4 images of 640x480 in 2 strips; renders in seconds; for unit tests";
      t.camera = {8.8, 20.0, 640, 480};
      t.flight = {{2, 2}, 120, 0.7, 0.35, 1.5, 0.03};
      t.scene.relief = 3;
      t.scene.relief_wavelength = 150;
      t.scene.road_spacing = 70;
      t.scene.squares = 1;
      t.scene.high_rises = 1;
      t.scene.water_share = 0.015;
      t.order = AngleOrder::kOmegaPhiKappa;
      t.unit = AngleUnit::kDegree;
      p.push_back(t);
    }
    {
      Preset s;
      s.name = "small";
      s.description = "2 strips x 5 images of 1000x750";
      s.camera = {8.8, 13.2, 1000, 750};
      s.flight = {{5, 5}, 150, 0.7, 0.35, 1.5, 0.04};
      s.scene.relief = 5;
      s.scene.relief_wavelength = 250;
      s.order = AngleOrder::kPhiOmegaKappa;
      s.unit = AngleUnit::kGon;
      p.push_back(s);
    }
    {
      // Canon EOS 400D (22.16 x 14.77 mm, 3888 x 2592 px), 24 mm lens, 700 m,
      // at a quarter of the resolution: 972 x 648 px of 22.8 um. The paper's
      // Table 2 steps about 50 m between exposures, and view selection has to
      // cope with such narrow bases: 50 m is 92.2 % forward overlap of the
      // 646 m footprint of image x, which flies along track here (the paper's
      // camera flew its 431 m short side along track: 88 %).
      Preset c;
      c.name = "campus";
      c.description =
          "the paper's campus: 4 strips of 16, 17, 18 and 16 images (67) at 700 m, 50 m bases "
          "(92.2 % forward, 30 % side overlap), 400D at 1/4 resolution";
      c.camera = {24.0, 22.16 / 972 * 1000, 972, 648};
      c.flight = {{16, 17, 18, 16}, 700, 0.922, 0.3, 1.5, 0.05};
      c.scene.relief = 6;
      c.scene.relief_wavelength = 900;
      c.scene.road_spacing = 140;
      c.scene.squares = 8;
      c.scene.building_density = 0.22;
      c.scene.building_min = 20;
      c.scene.building_max = 80;
      c.scene.high_rises = 3;
      c.scene.tree_density = 0.07;
      c.scene.water_share = 0.03;
      c.cell_per_gsd = 0.6;
      c.order = AngleOrder::kPhiOmegaKappa;  // the paper's Table 2 lists phi omega kappa
      c.unit = AngleUnit::kDegree;
      p.push_back(c);
    }
    {
      // The paper's Table 5: about 1,900 m above the ground (its 0.451 m GSD)
      // and about 108 m between exposures, 93.9 % of the 1,754 m footprint.
      // The relief stays a terrain's (220 m against 1,680 m to the highest
      // peaks still leaves 26 % side overlap there).
      Preset m;
      m.name = "mountain";
      m.description =
          "the paper's mountain block: large relief, heavy vegetation, few buildings; 5 strips x "
          "25 images (125) at 1900 m, 108 m bases (93.9 % forward, 35 % side overlap)";
      m.camera = {24.0, 22.16 / 972 * 1000, 972, 648};
      m.flight = {{25, 25, 25, 25, 25}, 1900, 0.9386, 0.35, 1.5, 0.05};
      m.scene.relief = 220;
      m.scene.relief_wavelength = 2500;
      m.scene.road_spacing = 0;
      m.scene.squares = 0;
      m.scene.building_density = 0.01;
      m.scene.high_rises = 0;
      m.scene.tree_density = 0.45;
      m.scene.water_share = 0.01;
      m.cell_per_gsd = 0.75;
      m.order = AngleOrder::kOmegaPhiKappa;
      m.unit = AngleUnit::kRadian;
      p.push_back(m);
    }
    {
      Preset c;
      c.name = "city";
      c.description =
          "buildings of many heights, like the paper's Vaihingen areas; 3 strips x 6 images";
      c.camera = {24.0, 22.16 / 972 * 1000, 972, 648};
      c.flight = {{6, 6, 6}, 500, 0.7, 0.35, 1.0, 0.04};
      c.scene.relief = 4;
      c.scene.relief_wavelength = 700;
      c.scene.road_spacing = 110;
      c.scene.squares = 3;
      c.scene.building_density = 0.4;
      c.scene.building_min = 15;
      c.scene.building_max = 60;
      c.scene.storey_max = 8;
      c.scene.pitched_share = 0.5;
      c.scene.high_rises = 8;
      c.scene.tree_density = 0.06;
      c.scene.water_share = 0.0;
      c.order = AngleOrder::kOmegaPhiKappa;
      c.unit = AngleUnit::kGon;  // like the Vaihingen orientations
      p.push_back(c);
    }
    {
      // A block big enough to show how a run scales (1,000 images, 180
      // groups) at an image size that keeps it within minutes on 2 cores:
      // tiny's camera and flight at half the resolution. The scene raster
      // grows with the ground (about 2.8 x 1.8 km); one cell per GSD keeps
      // it near 18 M cells (about 210 MB with the truth rasters) where tiny's half
      // GSD would take four times that.
      Preset l;
      l.name = "large";
      l.description =
          "20 strips x 50 images (1,000) of 320x240 at 120 m, 70 % forward and 35 % side "
          "overlap; for scaling runs (--strips and --strip-images fly a part of it)";
      l.camera = {8.8, 40.0, 320, 240};
      l.flight = {std::vector<int>(20, 50), 120, 0.7, 0.35, 1.5, 0.03};
      l.scene.relief = 8;
      l.scene.relief_wavelength = 600;
      l.scene.road_spacing = 90;
      l.scene.squares = 12;
      l.scene.high_rises = 6;
      l.scene.water_share = 0.015;
      l.cell_per_gsd = 1.0;
      l.order = AngleOrder::kOmegaPhiKappa;
      l.unit = AngleUnit::kDegree;
      p.push_back(l);
    }
    return p;
  }();
  return presets;
}

Preset FindPreset(const std::string& name) {
  std::string names;
  for (const Preset& p : AllPresets()) {
    if (p.name == name) return p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  throw Error("unknown preset '" + name + "': expected one of " + names);
}

double FlightPlan::NeighbourAngleDeg() const {
  return 2 * std::atan(base / (2 * flying_height)) * 180 / M_PI;
}

CameraSpec ScaledCamera(const CameraSpec& camera, double scale) {
  CameraSpec c = camera;
  c.width = std::max(16, static_cast<int>(std::lround(camera.width * scale)));
  c.height = std::max(16, static_cast<int>(std::lround(camera.height * scale)));
  // The sensor keeps its size: pixels grow as there are fewer of them.
  c.pixel_um = camera.pixel_um * camera.width / c.width;
  return c;
}

FlightPlan PlanFlight(const Preset& preset, const CameraSpec& camera, bool cross_strip,
                      double exposure, uint64_t seed) {
  const FlightSpec& f = preset.flight;
  FlightPlan plan;
  plan.gsd = f.flying_height * camera.pixel_um * 1e-3 / camera.focal_mm;
  const double along = camera.width * plan.gsd, across = camera.height * plan.gsd;
  const double base = (1 - f.forward_overlap) * along;
  const double spacing = (1 - f.side_overlap) * across;
  plan.flying_height = f.flying_height;
  plan.forward_overlap = f.forward_overlap;
  plan.side_overlap = f.side_overlap;
  plan.footprint_along = along;
  plan.footprint_across = across;
  plan.base = base;
  plan.strip_spacing = spacing;
  const int longest = *std::max_element(f.images_per_strip.begin(), f.images_per_strip.end());
  const int strips = static_cast<int>(f.images_per_strip.size());
  const double margin = 0.25 * std::max(along, across) + 2 * preset.scene.relief * 0.3;
  const double block_x = (longest - 1) * base + along;
  const double block_y = (strips - 1) * spacing + across;
  plan.scene_width = block_x + 2 * margin;
  plan.scene_height = block_y + 2 * margin;
  if (cross_strip) {
    // A cross strip flown along Y with the same forward overlap.
    plan.scene_height = std::max(plan.scene_height, block_y + along + 2 * margin);
  }
  std::mt19937_64 rng(seed * 7919 + 13);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_real_distribution<double> g(-exposure, exposure);
  const double x0 = margin + along / 2;
  const double y0 = plan.scene_height / 2 - (strips - 1) * spacing / 2;
  int index = 0;
  auto add = [&](int strip, double x, double y, double kappa) {
    PlannedImage im;
    char name[32];
    std::snprintf(name, sizeof(name), "IMG_%04d", ++index);
    im.name = name;
    im.strip = strip;
    im.center = {x + 0.02 * base * u(rng), y + 0.03 * spacing * u(rng),
                 f.flying_height * (1 + 0.01 * u(rng))};
    im.omega = f.attitude_noise * u(rng);
    im.phi = f.attitude_noise * u(rng);
    im.kappa = kappa + f.attitude_noise * 4 / 3 * u(rng);
    im.gain = 1 + g(rng);
    plan.images.push_back(im);
  };
  for (int s = 0; s < strips; ++s) {
    const int n = f.images_per_strip[s];
    // Shorter strips are centred on the longest.
    const double start = x0 + (longest - n) * base / 2;
    const double y = y0 + s * spacing;
    for (int i = 0; i < n; ++i) {
      const bool forward = s % 2 == 0;
      add(s, start + (forward ? i : n - 1 - i) * base, y, forward ? 0.0 : 180.0);
    }
  }
  plan.strips = strips;
  if (cross_strip) {
    const double x = plan.scene_width / 2;
    const int n = static_cast<int>(std::floor((plan.scene_height - 2 * margin - along) / base)) + 1;
    const double start = plan.scene_height / 2 - (n - 1) * base / 2;
    for (int i = 0; i < n; ++i) add(strips, x, start + i * base, 90.0);
    ++plan.strips;
  }
  return plan;
}

}  // namespace sapmvs::sim

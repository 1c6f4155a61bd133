#include "sapmvs/simulate/simulate.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "sapmvs/block/camera.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/output_folder.h"
#include "sapmvs/util/progress.h"
#include "simulate/sim_lidar.h"
#include "simulate/sim_ortho.h"
#include "simulate/sim_presets.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

// Projected CRS of the simulated coordinates: UTM 32N, where X ~ 5e5 and
// Y ~ 5.4e6 lie (southern Germany, like Vaihingen).
constexpr char kCrs[] = "EPSG:32632";

uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// A standard normal value from a hash, so that the noise of a pixel does not
// depend on which thread renders it.
double HashGauss(uint64_t key) {
  const uint64_t a = Mix(key), b = Mix(a ^ 0x5851f42d4c957f2dULL);
  const double u1 = (static_cast<double>(a >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  const double u2 = static_cast<double>(b >> 11) * (1.0 / 9007199254740992.0);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

cv::Mat Render(const sim::Scene& scene, const Camera& cam, const SimulateOptions& o, double gain,
               uint64_t image_key) {
  const int w = cam.width(), h = cam.height(), ss = o.supersampling;
  cv::Mat img(h, w, CV_8UC3);
  const Eigen::Vector3d sky(0.65, 0.72, 0.80);
#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      Eigen::Vector3d acc = Eigen::Vector3d::Zero();
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const Eigen::Vector2d uv(u - 0.5 + (sx + 0.5) / ss, v - 0.5 + (sy + 0.5) / ss);
          const sim::Hit hit = scene.Intersect(cam.center(), cam.Ray(uv));
          acc += hit.valid ? scene.Shade(hit) : sky;
        }
      }
      acc /= ss * ss;
      cv::Vec3b& px = img.at<cv::Vec3b>(v, u);
      for (int c = 0; c < 3; ++c) {
        const uint64_t key = image_key ^ ((static_cast<uint64_t>(v) * w + u) * 4 + c);
        const double value = sim::EncodeChannel(acc[c], gain) + o.noise * HashGauss(key);
        px[2 - c] = cv::saturate_cast<uchar>(std::lround(value));  // OpenCV stores BGR
      }
    }
  }
  return img;
}

void WriteText(const fs::path& path, const std::string& text) { WriteTextAtomically(path, text); }

void WritePng(const fs::path& path, const cv::Mat& image) {
  const std::vector<uchar> bytes = EncodeImage(image, ImageEncoding::kPng, path.string());
  WriteBytesAtomically(path, bytes.data(), bytes.size());
}

std::string Fixed(double v, int precision) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(precision) << v;
  return s.str();
}

std::string Number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The preset's description names its own overlaps; --overlap replaces them.
std::string Description(const sim::Preset& preset, const SimulateOptions& o) {
  if (o.overlap.empty()) return preset.description;
  return preset.description + ", here flown with --overlap " + Number(o.overlap[0]) + "," +
         Number(o.overlap[1]);
}

}  // namespace

namespace sim {

double EncodeChannel(double linear, double gain) {
  return 255.0 * std::pow(std::clamp(linear * gain, 0.0, 1.0), 1 / 2.2);
}

Eigen::Vector3d WorldOffset(double scene_width, double scene_height) {
  return {std::round(500000 - scene_width / 2), std::round(5400000 - scene_height / 2), 300};
}

}  // namespace sim

std::vector<std::string> SimulatePresetNames() {
  std::vector<std::string> names;
  for (const sim::Preset& p : sim::AllPresets()) names.push_back(p.name);
  return names;
}

std::string SimulateOptions::Problem() const {
  try {
    sim::FindPreset(preset);
    if (!angles.empty()) ParseAngleOrder(angles);
    if (!units.empty()) ParseAngleUnit(units);
  } catch (const Error& e) {
    return e.what();
  }
  if (out.empty()) return "no output folder given (--out DIR)";
  if (!(scale > 0 && scale <= 4)) return "--scale " + std::to_string(scale) + " is outside (0, 4]";
  if (supersampling < 1 || supersampling > 8) {
    return "--supersampling " + std::to_string(supersampling) + " is outside 1..8";
  }
  if (!(noise >= 0 && noise <= 50))
    return "--noise " + std::to_string(noise) + " is outside 0..50 grey levels";
  if (!(exposure <= 0.5)) return "--exposure " + std::to_string(exposure) + " is above 0.5";
  if (!overlap.empty()) {
    if (overlap.size() != 2) {
      std::string given;
      for (const double v : overlap) given += (given.empty() ? "" : ",") + Number(v);
      return "--overlap " + given + ": expected two values FWD,SIDE in percent, e.g. 88,30";
    }
    // Beyond these no block is flown: bases or strip spacings of a few
    // percent of the footprint.
    if (!(overlap[0] >= 0 && overlap[0] <= 95)) {
      return "--overlap forward " + Number(overlap[0]) + " % is outside [0, 95]";
    }
    if (!(overlap[1] >= 0 && overlap[1] <= 90)) {
      return "--overlap side " + Number(overlap[1]) + " % is outside [0, 90]";
    }
  }
  // A strip needs two images to overlap; beyond 10,000 images the scene
  // raster alone outgrows a workstation.
  if (strips < 0 || strips > 500)
    return "--strips " + std::to_string(strips) + " is outside 0..500";
  if (strip_images < 0 || strip_images > 1000) {
    return "--strip-images " + std::to_string(strip_images) + " is outside 0..1000";
  }
  if (strip_images == 1) return "--strip-images 1: expected at least 2 images per strip";
  return "";
}

sim::FlightPlan PlanSimulatedFlight(const SimulateOptions& o) {
  if (const std::string problem = o.Problem(); !problem.empty())
    throw Error("simulate: " + problem);
  sim::Preset preset = sim::FindPreset(o.preset);
  if (!o.overlap.empty()) {
    preset.flight.forward_overlap = o.overlap[0] / 100;
    preset.flight.side_overlap = o.overlap[1] / 100;
  }
  if (o.strips > 0 || o.strip_images > 0) {
    std::vector<int>& runs = preset.flight.images_per_strip;
    const int count = o.strips > 0 ? o.strips : static_cast<int>(runs.size());
    const int each =
        o.strip_images > 0 ? o.strip_images : *std::max_element(runs.begin(), runs.end());
    runs.assign(count, each);
  }
  const double exposure = o.exposure >= 0 ? o.exposure : preset.flight.exposure;
  return sim::PlanFlight(preset, sim::ScaledCamera(preset.camera, o.scale), o.cross_strip, exposure,
                         o.seed);
}

// Below SceneSpec's limit of 250 M cells, with room for rounding.
constexpr double kMaxSceneCells = 2.4e8;

SimulatedWorld BuildWorld(const SimulateOptions& o) {
  sim::FlightPlan plan = PlanSimulatedFlight(o);
  const sim::Preset preset = sim::FindPreset(o.preset);
  const sim::CameraSpec camera = sim::ScaledCamera(preset.camera, o.scale);
  sim::SceneSpec spec = preset.scene;
  spec.width = plan.scene_width;
  spec.height = plan.scene_height;
  // Cells of cell_per_gsd GSDs, or coarser where the scene would pass the
  // grid's 250 M cells (a 12 MP camera, --scale 4, over more than 20
  // images): the heights step at coarser cells, the texture, procedural,
  // keeps its detail at the pixel.
  spec.cell = std::max(plan.gsd * preset.cell_per_gsd,
                       std::sqrt(spec.width * spec.height / kMaxSceneCells));
  SimulatedWorld world{sim::Scene::Generate(spec, o.seed),
                       std::move(plan),
                       {},
                       camera.width,
                       camera.height,
                       camera.focal_mm,
                       camera.pixel_um};
  world.offset = sim::WorldOffset(world.scene.width(), world.scene.height());
  return world;
}

SimulateSummary Simulate(const SimulateOptions& o) {
  if (const std::string problem = o.Problem(); !problem.empty())
    throw Error("simulate: " + problem);
  // Claimed before the scene is built: a user's folder is refused at once.
  const OutputFolder folder(o.out, "simulate", {"images", "truth"});
  const sim::Preset preset = sim::FindPreset(o.preset);
  SimulateSummary summary;
  summary.order = o.angles.empty() ? preset.order : ParseAngleOrder(o.angles);
  summary.unit = o.units.empty() ? preset.unit : ParseAngleUnit(o.units);
  const SimulatedWorld world = [&] {
    Progress p("scene", 1, !o.quiet);
    SimulatedWorld w = BuildWorld(o);
    p.Advance();
    return w;
  }();
  const sim::Scene& scene = world.scene;
  const sim::FlightPlan& flight = world.flight;
  const Eigen::Vector3d& offset = world.offset;
  fs::create_directories(o.out / "images");
  fs::create_directories(o.out / "truth");
  const Intrinsics k =
      Intrinsics::FromFocalAndPixel(world.focal_mm, world.pixel_um, world.width, world.height);

  std::ostringstream orientation;
  orientation << "# sapmvs simulate --preset " << o.preset << " --seed " << o.seed << "\n"
              << "# name X Y Z "
              << (summary.order == AngleOrder::kOmegaPhiKappa ? "omega phi kappa"
                                                              : "phi omega kappa")
              << " (" << ToString(summary.unit) << ")\n";
  std::ostringstream exposure_txt;
  exposure_txt << "# name gain (the factor each image's linear radiance was multiplied by)\n";
  {
    Progress p("render", static_cast<long>(flight.images.size()), !o.quiet);
    for (size_t i = 0; i < flight.images.size(); ++i) {
      const PlannedImage& im = flight.images[i];
      const Camera cam = Camera::FromAngles(k, im.center, im.omega, im.phi, im.kappa,
                                            AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
      WritePng(o.out / "images" / (im.name + ".png"),
               Render(scene, cam, o, im.gain, Mix(o.seed * 1000003 + i)));
      const Eigen::Vector3d a =
          AnglesFromWorldToCamera(cam.rotation(), summary.order, summary.unit);
      const Eigen::Vector3d c = im.center + offset;
      const int digits = summary.unit == AngleUnit::kRadian ? 12 : 10;
      orientation << im.name << " " << Fixed(c.x(), 4) << " " << Fixed(c.y(), 4) << " "
                  << Fixed(c.z(), 4) << " " << Fixed(a[0], digits) << " " << Fixed(a[1], digits)
                  << " " << Fixed(a[2], digits) << "\n";
      exposure_txt << im.name << " " << Fixed(im.gain, 6) << "\n";
      p.Advance(1, im.name);
    }
  }
  WriteText(o.out / "orientation.txt", orientation.str());
  WriteText(o.out / "truth" / "exposure.txt", exposure_txt.str());

  std::ostringstream yaml;
  yaml << "# Synthetic block from `sapmvs simulate --preset " << o.preset << " --seed " << o.seed
       << "`: " << Description(preset, o) << ".\n"
       << "crs: \"" << kCrs << "\"\n"
       << "dem: truth/dsm.tif\n"
       << "camera:\n  name: " << preset.name << " camera\n"
       << "  width: " << world.width << "\n  height: " << world.height << "\n"
       << "  focal_mm: " << Fixed(world.focal_mm, 6) << "\n  pixel_um: " << Fixed(world.pixel_um, 9)
       << "\n"
       << "images: images\n"
       << "orientation:\n  file: orientation.txt\n  type: angles\n"
       << "  angles: " << ToString(summary.order) << "\n  units: " << ToString(summary.unit)
       << "\n";
  WriteText(o.out / "block.yaml", yaml.str());

  // The truth DSM: the cell tops, north-up.
  GeoRaster dsm;
  dsm.width = scene.nx();
  dsm.height = scene.ny();
  dsm.cell_size = scene.cell();
  dsm.origin_x = offset.x();
  dsm.origin_y = offset.y() + scene.ny() * scene.cell();
  dsm.crs = kCrs;
  dsm.values.resize(static_cast<size_t>(dsm.width) * dsm.height);
  for (int row = 0; row < dsm.height; ++row)
    for (int col = 0; col < dsm.width; ++col)
      dsm.at(col, row) =
          static_cast<float>(scene.CellHeight(col, dsm.height - 1 - row) + offset.z());
  WriteGeoTiff(o.out / "truth" / "dsm.tif", dsm);
  // The class of each DSM cell, so that checks can tell water (nothing to
  // match) and trees from ground and roofs.
  GeoRaster classes = dsm;
  for (int row = 0; row < dsm.height; ++row)
    for (int col = 0; col < dsm.width; ++col)
      classes.at(col, row) = sim::LasClass(scene.CellClass(col, dsm.height - 1 - row));
  WriteGeoTiff(o.out / "truth" / "classes.tif", classes);
  // The true orthophoto, at the images' nominal GSD over the DSM's extent.
  if (o.ortho) {
    sim::TrueOrtho ortho = sim::RenderTrueOrtho(scene, flight.gsd, o.supersampling);
    ortho.grid.origin_x += offset.x();
    ortho.grid.origin_y += offset.y();
    ortho.grid.crs = kCrs;
    WriteColorGeoTiff(o.out / "truth" / "ortho.tif", ortho.grid, ortho.rgba);
  }

  sim::LidarSpec lidar;
  lidar.density = sim::LidarDensityForGsd(flight.gsd);
  lidar.flying_height = std::max(300.0, 2 * preset.flight.flying_height / 3);
  const double m = 0.1 * std::min(scene.width(), scene.height());
  lidar.min = Eigen::Vector2d(m, m);
  lidar.max = Eigen::Vector2d(scene.width() - m, scene.height() - m);
  const std::vector<PointRecord> points = sim::SimulateLidar(scene, lidar, offset, o.seed);
  LasWriteOptions las;
  las.crs = kCrs;
  // A fixed date keeps the bytes a function of the seed (the paper's year).
  las.creation_day = 1;
  las.creation_year = 2016;
  WriteLas(o.out / "truth" / "lidar.las", points, las);
  if (o.xyz) WriteXyz(o.out / "truth" / "lidar.xyz", points, 3);

  summary.images = static_cast<int>(flight.images.size());
  summary.strips = flight.strips;
  summary.width = world.width;
  summary.height = world.height;
  summary.gsd = flight.gsd;
  summary.flying_height = flight.flying_height;
  summary.forward_overlap = flight.forward_overlap;
  summary.side_overlap = flight.side_overlap;
  summary.base = flight.base;
  summary.neighbour_angle = flight.NeighbourAngleDeg();
  summary.lidar_points = static_cast<long>(points.size());

  std::ostringstream readme;
  readme << "# Synthetic block: " << o.preset << " (seed " << o.seed << ")\n\n"
         << Description(preset, o) << ".\n\n"
         << "- `block.yaml`, `orientation.txt`: the block (" << summary.images << " images of "
         << world.width << "x" << world.height << " px in " << summary.strips << " strips; angles "
         << ToString(summary.order) << " in " << ToString(summary.unit) << "; CRS " << kCrs
         << ").\n"
         << "- `images/*.png`: rendered by ray casting the scene, " << o.supersampling << "x"
         << o.supersampling << " rays per pixel, Lambertian shading, sensor noise " << o.noise
         << " grey levels.\n"
         << "- `truth/dsm.tif`: the exact first-surface heights, " << Fixed(scene.cell(), 4)
         << " m cells (flat-topped: walls are vertical).\n"
         << "- `truth/classes.tif`: the LAS class of each DSM cell (2 ground, 5 vegetation, "
            "6 building, 9 water).\n"
         << (o.ortho ? "- `truth/ortho.tif`: the true orthophoto (RGBA, alpha 0 outside the "
                       "scene), " +
                           Fixed(flight.gsd, 4) +
                           " m cells from the DSM's north-west corner: the cell tops as seen "
                           "straight down, " +
                           std::to_string(o.supersampling) + "x" + std::to_string(o.supersampling) +
                           " points per cell, recorded with gain 1 and the images' tone curve, no "
                           "noise.\n"
                     : std::string())
         << "- `truth/lidar.las`" << (o.xyz ? " and `truth/lidar.xyz`" : "") << ": "
         << points.size() << " simulated first returns, " << Fixed(lidar.density, 2)
         << " points/m^2 per strip, "
         << "2 cm vertical and 5 cm horizontal noise; classes 2 ground, 5 vegetation, 6 building, "
            "9 water.\n"
         << "- `truth/exposure.txt`: each image's exposure gain.\n\n"
         << "Nominal GSD " << Fixed(flight.gsd, 4) << " m at " << flight.flying_height
         << " m above the mean ground; world = local + (" << Fixed(offset.x(), 0) << ", "
         << Fixed(offset.y(), 0) << ", " << Fixed(offset.z(), 0) << ").\n\n"
         << "Flight: " << Fixed(100 * flight.forward_overlap, 1) << " % forward and "
         << Fixed(100 * flight.side_overlap, 1) << " % side overlap"
         << (o.overlap.empty() ? " (the preset's)" : " (--overlap)") << " of the "
         << Fixed(flight.footprint_along, 1) << " x " << Fixed(flight.footprint_across, 1)
         << " m footprint (image x along track) at the mean ground: a base of "
         << Fixed(flight.base, 2) << " m between neighbours of a strip ("
         << Fixed(flight.NeighbourAngleDeg(), 2) << " deg between their rays to the ground "
         << "midway), strips " << Fixed(flight.strip_spacing, 2) << " m apart.\n";
  WriteText(o.out / "truth" / "README.md", readme.str());
  return summary;
}

}  // namespace sapmvs

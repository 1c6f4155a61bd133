#include "sapmvs/simulate/simulate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "cli_test_util.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/error.h"
#include "simulate/sim_presets.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

SimulateOptions Tiny(const fs::path& out, double scale = 1.0, int seed = 1) {
  SimulateOptions o = test::SimulatedOptions("tiny", seed, scale);
  o.out = out;
  return o;
}

using test::Slurp;

// The files simulate wrote, without the folder's marker (output_folder.h),
// which holds the writer's pid and so differs between runs.
std::vector<fs::path> FilesUnder(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const fs::path f = fs::relative(e.path(), dir);
    if (e.is_regular_file() && f != ".sapmvs_simulate") files.push_back(f);
  }
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Simulate, SameSeedSameBytesOtherSeedOtherImages) {
  // `a` is the folder the other tests share; `b` renders it again.
  const fs::path a = test::Simulated("tiny", 1, 0.5), dir = test::ScratchDir();
  SimulateOptions o = test::SimulatedOptions("tiny", 1, 0.5);
  o.out = dir / "b";
  const SimulateSummary summary = Simulate(o);
  EXPECT_EQ(static_cast<long>(ReadLas(dir / "b/truth/lidar.las").points.size()),
            summary.lidar_points);
  o.seed = 2;
  o.out = dir / "c";
  o.ortho = false;  // only its images are compared
  Simulate(o);
  EXPECT_FALSE(fs::exists(dir / "c/truth/ortho.tif"));
  const auto files = FilesUnder(a);
  ASSERT_EQ(files, FilesUnder(dir / "b"));
  EXPECT_TRUE(fs::is_regular_file(a / ".sapmvs_simulate"));
  ASSERT_GE(files.size(), 10u);  // block, orientation, 4 images, dsm, las, xyz, exposure, README
  for (const fs::path& f : files) {
    EXPECT_TRUE(Slurp(a / f) == Slurp(dir / "b" / f)) << f << " differs between runs";
  }
  EXPECT_FALSE(Slurp(a / "images/IMG_0001.png") == Slurp(dir / "c/images/IMG_0001.png"));
  // No temporary files are left behind.
  for (const fs::path& f : files) EXPECT_NE(f.filename().string().front(), '.') << f;
}

// Exposure gains from truth/exposure.txt.
std::map<std::string, double> Gains(const fs::path& dir) {
  std::ifstream in(dir / "truth" / "exposure.txt");
  std::map<std::string, double> g;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string name;
    double gain;
    s >> name >> gain;
    g[name] = gain;
  }
  return g;
}

double Pearson(const std::vector<double>& a, const std::vector<double>& b) {
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= a.size();
  mb /= b.size();
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

TEST(Simulate, DsmPointsProjectOntoTheirShadedTexture) {
  const fs::path dir = test::Simulated("tiny", 3);
  SimulateOptions o = test::SimulatedOptions("tiny", 3);
  o.out = dir;
  // Everything goes through the product's readers: block.yaml, GeoTIFF.
  const Block block = ReadBlock(dir / "block.yaml");
  ASSERT_EQ(block.images.size(), 4u);
  const GeoRaster dsm = ReadGeoRaster(dir / "truth" / "dsm.tif");
  const SimulatedWorld world = BuildWorld(o);
  const auto gains = Gains(dir);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> col(3, dsm.width - 4), row(3, dsm.height - 4);
  std::vector<double> predicted, rendered, shifted;
  for (const BlockImage& im : block.images) {
    const cv::Mat img = cv::imread(im.path.string(), cv::IMREAD_COLOR);
    ASSERT_EQ(img.cols, im.camera.width());
    const Eigen::Vector3d local_center = im.camera.center() - world.offset;
    for (int k = 0; k < 3000; ++k) {
      const int c = col(rng), r = row(rng);
      // Away from walls and crown edges: a flat 5x5 neighbourhood.
      double spread = 0;
      for (int dr = -2; dr <= 2; ++dr)
        for (int dc = -2; dc <= 2; ++dc)
          spread = std::max(spread, std::abs(dsm.at(c + dc, r + dr) - dsm.at(c, r)) * 1.0);
      if (spread > 0.3) continue;
      const Eigen::Vector2d xy = dsm.CellCenter(c, r);
      const Eigen::Vector3d world_pt(xy.x(), xy.y(), dsm.at(c, r));
      const Eigen::Vector2d uv = im.camera.Project(world_pt);
      if (!im.camera.InImage(uv, 3)) continue;
      // Visible: the first hit from the camera is the point itself.
      const Eigen::Vector3d local = world_pt - world.offset;
      const sim::Hit hit = world.scene.Intersect(local_center, (local - local_center).normalized());
      if (!hit.valid || (hit.point - local).norm() > 2 * world.scene.cell()) continue;
      const sim::Hit top = world.scene.TopAt(local.x(), local.y());
      if (top.cls == sim::SurfaceClass::kWater) continue;
      const double expect =
          sim::EncodeChannel(world.scene.Shade(top)[1], gains.at(im.name));  // green
      const int u = static_cast<int>(std::lround(uv.x())),
                v = static_cast<int>(std::lround(uv.y()));
      predicted.push_back(expect);
      rendered.push_back(img.at<cv::Vec3b>(v, u)[1]);
      shifted.push_back(img.at<cv::Vec3b>(v + 3, u + 3)[1]);
    }
  }
  ASSERT_GE(predicted.size(), 1000u);
  auto median_abs_diff = [&](const std::vector<double>& values) {
    std::vector<double> d;
    for (size_t i = 0; i < predicted.size(); ++i) d.push_back(std::abs(predicted[i] - values[i]));
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    return d[d.size() / 2];
  };
  const double r_at = Pearson(predicted, rendered), r_off = Pearson(predicted, shifted);
  const double d_at = median_abs_diff(rendered), d_off = median_abs_diff(shifted);
  std::cout << "[ sim ] " << predicted.size() << " points: correlation " << r_at
            << ", median |difference| " << d_at << " grey levels; 3 px off: " << r_off << ", "
            << d_off << "\n";
  // A pixel averages 2x2 rays over its footprint while the prediction is a
  // point sample, and there is sensor noise: close, not equal.
  EXPECT_GT(r_at, 0.95);
  EXPECT_LT(d_at, 4.0);
  // Three pixels off, the texture no longer matches (the shading and the
  // class colours still correlate).
  EXPECT_GT(d_off, 3 * d_at);
  EXPECT_LT(r_off, r_at - 0.05);
}

TEST(Simulate, TruthFilesAreValidAndAgree) {
  const fs::path dir = test::Simulated("tiny", 3);
  const GeoRaster dsm = ReadGeoRaster(dir / "truth" / "dsm.tif");
  EXPECT_NE(dsm.crs.find("32632"), std::string::npos);
  // UTM-like coordinates, so float32 mistakes show.
  EXPECT_GT(dsm.origin_x, 4.9e5);
  EXPECT_GT(dsm.origin_y, 5.39e6);
  const LasCloud las = ReadLas(dir / "truth" / "lidar.las");
  EXPECT_EQ(ReadXyz(dir / "truth" / "lidar.xyz").points.size(), las.points.size());
  EXPECT_FALSE(las.crs_wkt.empty());
  ASSERT_GT(las.points.size(), 10000u);
  // Ground returns lie on the DSM (2 cm vertical noise, 5 cm horizontal on
  // gentle slopes); the density is about what the README promises.
  std::vector<double> dz;
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const PointRecord& p : las.points) {
    xmin = std::min(xmin, p.x), xmax = std::max(xmax, p.x), ymin = std::min(ymin, p.y),
    ymax = std::max(ymax, p.y);
    if (p.classification != 2) continue;
    const int c = static_cast<int>((p.x - dsm.origin_x) / dsm.cell_size);
    const int r = static_cast<int>((dsm.origin_y - p.y) / dsm.cell_size);
    if (c < 1 || r < 1 || c >= dsm.width - 1 || r >= dsm.height - 1) continue;
    dz.push_back(std::abs(p.z - dsm.at(c, r)));
  }
  ASSERT_GT(dz.size(), 1000u);
  std::nth_element(dz.begin(), dz.begin() + dz.size() / 2, dz.end());
  EXPECT_LT(dz[dz.size() / 2], 0.05);
  const double density = las.points.size() / ((xmax - xmin) * (ymax - ymin));
  EXPECT_GT(density, 1.0);
  EXPECT_LT(density, 4.0 * 2.5);  // strips overlap
  // The class raster lies on the DSM's grid, holds LAS codes only, and agrees
  // with the LiDAR's classes, which come from ray hits, not from the raster
  // (walls and the 5 cm horizontal noise make the few that differ).
  const GeoRaster classes = ReadGeoRaster(dir / "truth" / "classes.tif");
  ASSERT_EQ(classes.width, dsm.width);
  ASSERT_EQ(classes.height, dsm.height);
  EXPECT_EQ(classes.origin_x, dsm.origin_x);
  EXPECT_EQ(classes.origin_y, dsm.origin_y);
  EXPECT_EQ(classes.cell_size, dsm.cell_size);
  std::map<int, long> cells;
  for (const float v : classes.values) ++cells[static_cast<int>(v)];
  for (const auto& [k, n] : cells) EXPECT_TRUE(k == 2 || k == 5 || k == 6 || k == 9) << k;
  EXPECT_GT(cells[2], cells[6]);
  EXPECT_GT(cells[6], 0);
  long agree = 0, total = 0;
  for (const PointRecord& p : las.points) {
    const int c = static_cast<int>((p.x - classes.origin_x) / classes.cell_size);
    const int r = static_cast<int>((classes.origin_y - p.y) / classes.cell_size);
    if (c < 0 || r < 0 || c >= classes.width || r >= classes.height) continue;
    ++total;
    agree += static_cast<int>(classes.at(c, r)) == p.classification;
  }
  ASSERT_GT(total, 10000);
  EXPECT_GT(static_cast<double>(agree) / total, 0.95) << agree << " of " << total;
  // The README says how the block was flown.
  const std::string readme = Slurp(dir / "truth" / "README.md");
  EXPECT_NE(readme.find("70.0 % forward and 35.0 % side overlap (the preset's)"), std::string::npos)
      << readme;
  EXPECT_NE(readme.find("a base of 52.36 m"), std::string::npos) << readme;
}

TEST(Simulate, AngleFlagsChangeTheFileNotTheCameras) {
  const fs::path dir = test::ScratchDir();
  SimulateOptions base = Tiny(dir / "base", 0.25);
  base.ortho = false;  // the cameras are compared, not the truth
  Simulate(base);
  const Block ref = ReadBlock(dir / "base" / "block.yaml");
  for (const char* order : {"omega-phi-kappa", "phi-omega-kappa"}) {
    for (const char* unit : {"deg", "gon", "rad"}) {
      SimulateOptions o = Tiny(dir / (std::string(order) + unit), 0.25);
      o.angles = order;
      o.units = unit;
      o.ortho = false;
      Simulate(o);
      const std::string yaml = Slurp(o.out / "block.yaml");
      EXPECT_NE(yaml.find(std::string("angles: ") + order), std::string::npos);
      EXPECT_NE(yaml.find(std::string("units: ") + unit), std::string::npos);
      const Block b = ReadBlock(o.out / "block.yaml");
      ASSERT_EQ(b.images.size(), ref.images.size());
      for (size_t i = 0; i < b.images.size(); ++i) {
        EXPECT_LT(
            (b.images[i].camera.rotation() - ref.images[i].camera.rotation()).cwiseAbs().maxCoeff(),
            1e-9)
            << order << " " << unit;
      }
    }
  }
}

TEST(Simulate, PresetsDescribeThePapersBlocks) {
  for (const std::string& name : SimulatePresetNames()) {
    SimulateOptions o;
    o.preset = name;
    o.out = "unused";
    o.scale = 0.05;  // plans only; nothing is rendered here
    EXPECT_TRUE(o.Check()) << name;
  }
  SimulateOptions campus;
  campus.preset = "campus";
  campus.out = "unused";
  const sim::FlightPlan w = PlanSimulatedFlight(campus);
  EXPECT_EQ(w.images.size(), 67u);
  EXPECT_EQ(w.strips, 4);
  int per_strip[4] = {0, 0, 0, 0};
  for (const PlannedImage& im : w.images) ++per_strip[im.strip];
  EXPECT_EQ(per_strip[0], 16);
  EXPECT_EQ(per_strip[1], 17);
  EXPECT_EQ(per_strip[2], 18);
  EXPECT_EQ(per_strip[3], 16);
}

TEST(Simulate, CrossStripFliesAcrossTheOthers) {
  SimulateOptions o;
  o.preset = "small";
  o.out = "unused";
  o.scale = 0.1;  // plans only
  const sim::FlightPlan plain = PlanSimulatedFlight(o);
  o.cross_strip = true;
  const sim::FlightPlan cross = PlanSimulatedFlight(o);
  EXPECT_EQ(cross.strips, plain.strips + 1);
  ASSERT_GT(cross.images.size(), plain.images.size() + 1);
  // The added images fly along +Y: kappa near 90 deg, x fixed, y increasing.
  const PlannedImage& a = cross.images[plain.images.size()];
  const PlannedImage& b = cross.images.back();
  EXPECT_NEAR(a.kappa, 90, 3);
  EXPECT_GT(b.center.y() - a.center.y(), 10 * std::abs(b.center.x() - a.center.x()));
}

// Mean step between consecutive exposures along a strip, and between the
// mean centres of neighbouring strips, from the planned cameras alone.
struct Spacings {
  double base = 0, strips = 0;
};
Spacings MeasureSpacings(const sim::FlightPlan& plan) {
  std::map<int, std::vector<Eigen::Vector3d>> by_strip;
  for (const PlannedImage& im : plan.images) by_strip[im.strip].push_back(im.center);
  Spacings s;
  int pairs = 0;
  std::vector<double> strip_y;
  for (const auto& [strip, centres] : by_strip) {
    // Along the strip only: the cross-track position noise says nothing
    // about the base.
    const Eigen::Vector3d along = (centres.back() - centres.front()).normalized();
    double y = 0;
    for (size_t i = 0; i < centres.size(); ++i) {
      y += centres[i].y();
      if (i == 0) continue;
      s.base += along.dot(centres[i] - centres[i - 1]);
      ++pairs;
    }
    strip_y.push_back(y / centres.size());
  }
  s.base /= pairs;
  for (size_t k = 1; k < strip_y.size(); ++k) s.strips += strip_y[k] - strip_y[k - 1];
  s.strips /= strip_y.size() - 1;
  return s;
}

// Footprint of the preset's sensor on the mean ground, image x (along track)
// and image y, from the camera's data sheet rather than the plan.
Eigen::Vector2d SensorFootprint(const std::string& preset) {
  const sim::Preset p = sim::FindPreset(preset);
  const double scale = p.flight.flying_height / p.camera.focal_mm * 1e-3;
  return Eigen::Vector2d(p.camera.width, p.camera.height) * p.camera.pixel_um * scale;
}

TEST(Simulate, OverlapFlagSetsBaseAndStripSpacing) {
  for (const std::string preset : {"small", "campus", "mountain"}) {
    const Eigen::Vector2d footprint = SensorFootprint(preset);
    for (const auto& [forward, side] : {std::pair{88.0, 30.0}, {60.0, 20.0}, {95.0, 0.0}}) {
      SimulateOptions o;
      o.preset = preset;
      o.out = "unused";
      o.overlap = {forward, side};
      const sim::FlightPlan plan = PlanSimulatedFlight(o);
      const Spacings measured = MeasureSpacings(plan);
      const double base = (1 - forward / 100) * footprint.x();
      const double spacing = (1 - side / 100) * footprint.y();
      EXPECT_NEAR(measured.base, base, 0.03 * base) << preset << " " << forward;
      EXPECT_NEAR(measured.strips, spacing, 0.03 * spacing) << preset << " " << side;
      EXPECT_NEAR(plan.base, base, 1e-6 * base);
      EXPECT_NEAR(plan.forward_overlap, forward / 100, 1e-12);
      EXPECT_NEAR(plan.side_overlap, side / 100, 1e-12);
    }
  }
  // The preset's own overlaps given as a flag fly the very same cameras.
  SimulateOptions o;
  o.preset = "tiny";
  o.out = "unused";
  const sim::FlightPlan preset = PlanSimulatedFlight(o);
  o.overlap = {70, 35};
  const sim::FlightPlan given = PlanSimulatedFlight(o);
  ASSERT_EQ(given.images.size(), preset.images.size());
  for (size_t i = 0; i < given.images.size(); ++i) {
    EXPECT_EQ(given.images[i].center, preset.images[i].center);
    EXPECT_EQ(given.images[i].kappa, preset.images[i].kappa);
  }
}

TEST(Simulate, StripFlagsCutTheLargeFlight) {
  SimulateOptions o;
  o.preset = "large";
  o.out = "unused";
  const sim::FlightPlan whole = PlanSimulatedFlight(o);
  EXPECT_EQ(whole.images.size(), 1000u);
  EXPECT_EQ(whole.strips, 20);
  o.strips = 5;
  o.strip_images = 20;
  const sim::FlightPlan part = PlanSimulatedFlight(o);
  ASSERT_EQ(part.images.size(), 100u);
  EXPECT_EQ(part.strips, 5);
  // The same flight cut shorter: camera, GSD, base and strip spacing stay.
  EXPECT_EQ(part.gsd, whole.gsd);
  EXPECT_EQ(part.base, whole.base);
  EXPECT_EQ(part.strip_spacing, whole.strip_spacing);
  std::map<int, int> per_strip;
  for (const PlannedImage& im : part.images) ++per_strip[im.strip];
  for (const auto& [strip, n] : per_strip) EXPECT_EQ(n, 20) << "strip " << strip;
  // One flag alone keeps the preset's other count (campus: 4 strips, longest 18).
  SimulateOptions c;
  c.preset = "campus";
  c.out = "unused";
  c.strips = 2;
  EXPECT_EQ(PlanSimulatedFlight(c).images.size(), 36u);
  c.strips = 0;
  c.strip_images = 3;
  EXPECT_EQ(PlanSimulatedFlight(c).images.size(), 12u);
  for (const auto& [strips, images] : {std::pair{-1, 0}, {501, 0}, {0, 1}, {0, 1001}}) {
    c.strips = strips;
    c.strip_images = images;
    EXPECT_FALSE(c.Problem().empty()) << strips << " " << images;
    EXPECT_THROW(PlanSimulatedFlight(c), Error);
  }
}

TEST(Simulate, CampusAndMountainFlyThePapersBases) {
  // Table 2: about 50 m between exposures at 700 m; Table 5: about 108 m
  // at about 1,900 m (GSD 0.451 m at full resolution).
  const struct {
    const char* preset;
    double height, base, angle;
  } blocks[] = {{"campus", 700, 50, 4.1}, {"mountain", 1900, 108, 3.25}};
  for (const auto& b : blocks) {
    SimulateOptions o;
    o.preset = b.preset;
    o.out = "unused";
    const sim::FlightPlan plan = PlanSimulatedFlight(o);
    double z = 0;
    for (const PlannedImage& im : plan.images) z += im.center.z();
    EXPECT_NEAR(z / plan.images.size(), b.height, 0.005 * b.height) << b.preset;
    const double base = MeasureSpacings(plan).base;
    EXPECT_NEAR(base, b.base, 0.03 * b.base) << b.preset;
    const double angle = 2 * std::atan(base / (2 * b.height)) * 180 / M_PI;
    EXPECT_NEAR(angle, b.angle, 0.1) << b.preset;
    EXPECT_NEAR(plan.NeighbourAngleDeg(), b.angle, 0.1) << b.preset;
    std::cout << "[ sim ] " << b.preset << ": " << 100 * plan.forward_overlap << " % forward, "
              << 100 * plan.side_overlap << " % side overlap at " << plan.flying_height
              << " m; base " << base << " m measured (" << plan.base << " planned), " << angle
              << " deg between neighbours; strips " << plan.strip_spacing << " m apart\n";
  }
  SimulateOptions mountain;
  mountain.preset = "mountain";
  mountain.out = "unused";
  EXPECT_NEAR(PlanSimulatedFlight(mountain).gsd * 972 / 3888, 0.451, 0.01);
}

TEST(Simulate, BadOverlapIsRefusedInOneLine) {
  const struct {
    std::vector<double> overlap;
    const char* says;
  } cases[] = {{{96, 30}, "forward 96 % is outside [0, 95]"},
               {{-1, 30}, "forward -1 % is outside [0, 95]"},
               {{NAN, 30}, "forward nan % is outside [0, 95]"},
               {{88, 91}, "side 91 % is outside [0, 90]"},
               {{88, -0.5}, "side -0.5 % is outside [0, 90]"},
               {{88}, "--overlap 88: expected two values"},
               {{88, 30, 10}, "--overlap 88,30,10: expected two values"}};
  for (const auto& c : cases) {
    SimulateOptions o = Tiny("unused");
    o.overlap = c.overlap;
    const std::string problem = o.Problem();
    EXPECT_NE(problem.find(c.says), std::string::npos) << problem;
    EXPECT_EQ(problem.find('\n'), std::string::npos) << problem;
    EXPECT_THROW(PlanSimulatedFlight(o), Error);
  }
  for (const auto& good : {std::vector<double>{0, 0}, {95, 90}, {88, 30}}) {
    SimulateOptions o = Tiny("unused");
    o.overlap = good;
    EXPECT_EQ(o.Problem(), "");
  }
  // The command line refuses before anything is written.
  const fs::path out = test::ScratchDir() / "refused";
  const test::CliResult r =
      test::RunCli("simulate --preset tiny --overlap 96,30 --out " + out.string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--overlap forward 96 % is outside [0, 95]"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST(Simulate, BadOptionsAreRejected) {
  SimulateOptions o = Tiny(test::ScratchDir());
  o.preset = "moon";
  try {
    Simulate(o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown preset 'moon'"), std::string::npos) << e.what();
  }
  o = Tiny(test::ScratchDir());
  o.scale = 0;
  EXPECT_THROW(Simulate(o), Error);
  o = Tiny(test::ScratchDir());
  o.units = "grad-ish";
  EXPECT_THROW(Simulate(o), Error);
  EXPECT_FALSE(o.Check());
}

}  // namespace
}  // namespace sapmvs

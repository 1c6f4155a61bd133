#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::SharedDir;
using test::TestDir;

// ODM pairs look at the ground from opposite sides at 30 deg tilt: the data's
// README measured 0.11 to 0.64 per pair; here 0.39 to 0.75, mean 0.53.
constexpr double kOdmMinMeanNcc = 0.4;

fs::path NgiBlock() { return TestDir() / "blocks" / "ngi.yaml"; }

struct DerivedCamera {
  int w, h;
  double fx, fy, cx, cy;
  Eigen::Matrix3d r;
  Eigen::Vector3d c;
};

// derived/*/cameras_opencv.txt: name W H fx fy cx cy k1 k2 p1 p2 k3 R(9) C(3),
// written independently by the dataset's preparer from the same sources.
std::map<std::string, DerivedCamera> ReadDerived(const fs::path& path) {
  std::ifstream in(path);
  std::map<std::string, DerivedCamera> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string name;
    DerivedCamera d;
    double dist[5];
    s >> name >> d.w >> d.h >> d.fx >> d.fy >> d.cx >> d.cy;
    for (double& k : dist) s >> k;
    for (int i = 0; i < 9; ++i) s >> d.r(i / 3, i % 3);
    s >> d.c.x() >> d.c.y() >> d.c.z();
    out[fs::path(name).stem().string()] = d;
  }
  return out;
}

TEST(YamlReaderNgi, ReadsFourImagesMatchingTheIndependentConversion) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/ngi");
  const Block block = ReadBlock(NgiBlock());
  EXPECT_EQ(block.format, "yaml");
  ASSERT_EQ(block.images.size(), 4u);
  const auto derived =
      ReadDerived(SharedDir() / "datasets/orthority_ngi_odm/derived/ngi/cameras_opencv.txt");
  ASSERT_EQ(derived.size(), 4u);
  for (const BlockImage& im : block.images) {
    EXPECT_EQ(im.camera.width(), 640);
    EXPECT_EQ(im.camera.height(), 1152);
    const DerivedCamera& d = derived.at(im.name);
    EXPECT_NEAR(im.camera.intrinsics().fx, d.fx, 1e-5);
    EXPECT_NEAR(im.camera.intrinsics().cx, d.cx, 1e-9);
    EXPECT_NEAR(im.camera.intrinsics().cy, d.cy, 1e-9);
    EXPECT_LT((im.camera.rotation() - d.r).cwiseAbs().maxCoeff(), 1e-9) << im.name;
    EXPECT_LT((im.camera.center() - d.c).norm(), 1e-6);
  }
  EXPECT_FALSE(block.crs.empty());
  // The local origin is a round number near the camera centres.
  EXPECT_LT(std::abs(block.origin.x() - (-56392)), 2.0);
}

TEST(YamlReaderNgi, DemPointsLandOnPhotoConsistentSpots) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/derived/ngi/dem_points.xyz");
  const Block block = ReadBlock(NgiBlock());
  const auto points =
      test::ReadXyz(SharedDir() / "datasets/orthority_ngi_odm/derived/ngi/dem_points.xyz", 3);
  std::vector<LoadedImage> images;
  for (const BlockImage& im : block.images) images.push_back(LoadUndistorted(im));
  std::vector<std::string> names;
  for (const BlockImage& im : block.images) names.push_back(im.name);
  const test::BlockNcc ncc = test::MeasureBlockNcc(images, names, points);
  ASSERT_GE(ncc.pairs, 4) << "the NGI images overlap in at least 4 pairs";
  EXPECT_GE(ncc.mean, 0.6);
  // Diagonal cross-strip pairs see relief and trees from far apart, and the
  // DEM is a terrain model, so single pairs may sit below the average.
  EXPECT_GE(ncc.worst, 0.4);
  EXPECT_GE(ncc.worst_margin, 0.3) << "a 20 px shift must destroy the correlation";
}

// Writes a block.yaml and an orientation file into `dir`.
fs::path WriteBlock(const fs::path& dir, const std::string& yaml, const std::string& orientation) {
  std::ofstream(dir / "orientation.txt") << orientation;
  std::ofstream(dir / "block.yaml") << yaml;
  return dir / "block.yaml";
}

std::string NgiYaml(const std::string& orientation_keys, const std::string& camera_keys = "") {
  const fs::path ngi = SharedDir() / "datasets/orthority_ngi_odm/ngi";
  return "camera:\n  width: 640\n  height: 1152\n" +
         (camera_keys.empty() ? std::string("  focal_mm: 120\n  sensor_mm: [92.160, 165.888]\n")
                              : camera_keys) +
         "images: " + ngi.string() + "\norientation:\n  file: orientation.txt\n" + orientation_keys;
}

TEST(YamlReaderOdm, UndistortedImagesArePhotoConsistentWithTheDsm) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/derived/odm/dsm_points.xyz");
  const Block block = ReadBlock(TestDir() / "blocks" / "odm.yaml");
  ASSERT_EQ(block.images.size(), 4u);
  EXPECT_FALSE(block.images[0].camera.intrinsics().distortion.IsZero());
  const auto points =
      test::ReadXyz(SharedDir() / "datasets/orthority_ngi_odm/derived/odm/dsm_points.xyz", 3);
  std::vector<LoadedImage> undistorted, raw;
  std::vector<std::string> names;
  for (const BlockImage& im : block.images) {
    undistorted.push_back(LoadUndistorted(im));
    raw.push_back({LoadImage(im), im.camera.Pinhole()});
    names.push_back(im.name);
  }
  const test::BlockNcc good = test::MeasureBlockNcc(undistorted, names, points);
  std::cout << "[ ncc ] the same without undistortion:\n";
  const test::BlockNcc bad = test::MeasureBlockNcc(raw, names, points);
  ASSERT_GE(good.pairs, 4);
  EXPECT_GE(good.mean, kOdmMinMeanNcc);
  EXPECT_GE(good.worst_margin, 0.25);
  EXPECT_LT(bad.mean, good.mean - 0.3) << "undistortion must matter";
}

TEST(YamlReader, EveryOrientationTypeAndConventionGivesTheSameCameras) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/ngi");
  const Block ref = ReadBlock(NgiBlock());
  const fs::path dir = test::ScratchDir();
  struct Variant {
    std::string keys;
    std::function<std::string(const Camera&)> line;
  };
  auto angles = [](AngleOrder o, AngleUnit u) {
    return [o, u](const Camera& c) {
      const Eigen::Vector3d a = AnglesFromWorldToCamera(c.rotation(), o, u);
      std::ostringstream s;
      s.precision(17);
      s << c.center().transpose() << " " << a.transpose();
      return s.str();
    };
  };
  std::vector<Variant> variants;
  for (AngleOrder o : {AngleOrder::kOmegaPhiKappa, AngleOrder::kPhiOmegaKappa}) {
    for (AngleUnit u : {AngleUnit::kDegree, AngleUnit::kGon, AngleUnit::kRadian}) {
      variants.push_back(
          {"  angles: " + ToString(o) + "\n  units: " + ToString(u) + "\n", angles(o, u)});
    }
  }
  variants.push_back(
      {"  type: rotation\n  rotation: world-to-camera-opencv\n", [](const Camera& c) {
         std::ostringstream s;
         s.precision(17);
         s << c.center().transpose();
         for (int i = 0; i < 9; ++i) s << " " << c.rotation()(i / 3, i % 3);
         return s.str();
       }});
  variants.push_back({"  type: rotation\n  rotation: camera-to-world\n", [](const Camera& c) {
                        const Eigen::Matrix3d r = c.rotation().transpose() * PhotoToOpenCv();
                        std::ostringstream s;
                        s.precision(17);
                        s << c.center().transpose();
                        for (int i = 0; i < 9; ++i) s << " " << r(i / 3, i % 3);
                        return s.str();
                      }});
  variants.push_back({"  type: projection\n", [](const Camera& c) {
                        const Eigen::Matrix<double, 3, 4> p = c.ProjectionMatrix() / 1000.0;
                        std::ostringstream s;
                        s.precision(17);
                        for (int i = 0; i < 12; ++i) s << (i ? " " : "") << p(i / 4, i % 4);
                        return s.str();
                      }});
  for (const Variant& v : variants) {
    std::string ori = "# converted from the NGI block\n";
    for (const BlockImage& im : ref.images) ori += im.name + " " + v.line(im.camera) + "\n";
    const Block b = ReadBlock(WriteBlock(dir, NgiYaml(v.keys), ori));
    ASSERT_EQ(b.images.size(), ref.images.size()) << v.keys;
    for (size_t i = 0; i < b.images.size(); ++i) {
      const Eigen::Vector3d x = ref.images[i].camera.BackProject({100.25, 900.5}, 4800);
      EXPECT_LT((b.images[i].camera.Project(x) - ref.images[i].camera.Project(x)).norm(), 1e-6)
          << v.keys;
    }
  }
}

struct YamlMalformed {
  std::string name;
  std::string orientation_keys;
  std::string orientation;
  std::string camera_keys;
  std::string expect_file;  // block.yaml or orientation.txt
  int expect_line;
  std::string expect_text;
};

// Keeps ctest's discovered test names stable (no byte dumps).
void PrintTo(const YamlMalformed& m, std::ostream* os) { *os << m.name; }

class YamlReaderMalformed : public ::testing::TestWithParam<YamlMalformed> {};

TEST_P(YamlReaderMalformed, FailsNamingFileAndLine) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/ngi");
  const YamlMalformed m = GetParam();
  const fs::path dir = test::ScratchDir();
  const fs::path yaml = WriteBlock(dir, NgiYaml(m.orientation_keys, m.camera_keys), m.orientation);
  test::ExpectInputError([&] { ReadBlock(yaml); }, m.expect_file, m.expect_line, m.expect_text);
}

const std::string kGoodLine =
    "3324c_2015_1004_05_0182_RGB -55094.504480 -3727407.037480 5258.307930 -0.349216 0.298484 "
    "-179.086702\n";
const std::string kOpk = "  angles: omega-phi-kappa\n  units: deg\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, YamlReaderMalformed,
    ::testing::Values(
        YamlMalformed{"TooFewFields", kOpk, kGoodLine + "3324c_2015_1004_05_0184_RGB 1 2 3 4 5\n",
                      "", "orientation.txt", 2, "expected 7 fields"},
        YamlMalformed{"NotANumber", kOpk, "# header\n\n3324c_2015_1004_05_0182_RGB 1 2 3 x 5 6\n",
                      "", "orientation.txt", 3, "got 'x'"},
        YamlMalformed{"NaN", kOpk, "3324c_2015_1004_05_0182_RGB 1 2 nan 4 5 6\n", "",
                      "orientation.txt", 1, "finite"},
        YamlMalformed{"UnknownImage", kOpk, kGoodLine + "no_such_image 1 2 3 4 5 6\n", "",
                      "orientation.txt", 2, "no image for 'no_such_image'"},
        YamlMalformed{"UnknownUnit", "  angles: omega-phi-kappa\n  units: degs\n", kGoodLine, "",
                      "block.yaml", 10, "unknown angle unit 'degs'"},
        YamlMalformed{"MissingUnits", "  angles: omega-phi-kappa\n", kGoodLine, "", "block.yaml", 8,
                      "missing key 'units'"},
        YamlMalformed{"CameraWithoutPixelSize", kOpk, kGoodLine, "  focal_mm: 120\n", "block.yaml",
                      2, "needs pixel_um or sensor_mm"},
        YamlMalformed{
            "BadDistortionTerm", kOpk, kGoodLine,
            "  fx: 833\n  fy: 833\n  cx: 319.5\n  cy: 575.5\n  distortion: {k1: 0.1, k9: 1}\n",
            "block.yaml", 8, "unknown distortion term 'k9'"}),
    [](const auto& p) { return p.param.name; });

TEST(YamlReader, WrongImageSizeIsReported) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets/orthority_ngi_odm/ngi");
  const fs::path dir = test::ScratchDir();
  std::string yaml = NgiYaml(kOpk);
  yaml.replace(yaml.find("width: 640"), 10, "width: 641");
  try {
    ReadBlock(WriteBlock(dir, yaml, kGoodLine));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("image is 640x1152 px, its camera expects 641x1152"),
              std::string::npos)
        << e.what();
  }
}

TEST(YamlReader, InvalidYamlNamesTheLine) {
  const fs::path dir = test::ScratchDir();
  std::ofstream(dir / "block.yaml") << "camera:\n  width: 640\n  height: [1152\n";
  try {
    ReadBlock(dir / "block.yaml");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_GT(e.line(), 0);
    EXPECT_NE(std::string(e.what()).find("block.yaml:"), std::string::npos);
  }
}

// Found by fuzzing (scripts/fuzz.sh block_yaml): an image folder name longer
// than the system allows escaped as std::filesystem_error, not as a line that
// names block.yaml.
TEST(YamlReader, ImageFolderNameTooLongNamesTheLine) {
  const fs::path dir = test::ScratchDir();
  std::ofstream(dir / "block.yaml")
      << "camera: {width: 8, height: 6, focal_mm: 6, pixel_um: 2}\nimages: "
      << std::string(5000, 'x') << "\norientation: {file: o.txt}\n";
  try {
    ReadBlock(dir / "block.yaml");
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_NE(std::string(e.what()).find("image folder not found"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

#include "block/orientation_export.h"

#include <gtest/gtest.h>

#include <fstream>

#include "bad_inputs_fixture.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/rotation.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::ReadText;
using test::ReplaceAll;
using test::WriteText;

fs::path Blocks() { return test::TestDir() / "blocks"; }
fs::path NgiData() { return test::SharedDir() / "datasets/orthority_ngi_odm/ngi"; }

// Every camera of `got` equals the one of the same image (by stem) in `want`:
// centres within 1e-6 m, rotations within 1e-9.
void ExpectSameCameras(const Block& got, const Block& want) {
  ASSERT_EQ(got.images.size(), want.images.size());
  for (const BlockImage& im : got.images) {
    const int w = want.FindImage(fs::path(im.name).stem().string());
    ASSERT_GE(w, 0) << im.name;
    const Camera& a = im.camera;
    const Camera& b = want.images[w].camera;
    EXPECT_EQ(fs::weakly_canonical(im.path), fs::weakly_canonical(want.images[w].path));
    EXPECT_LT((a.center() - b.center()).norm(), 1e-6) << im.name;
    EXPECT_LT((a.rotation() - b.rotation()).cwiseAbs().maxCoeff(), 1e-9) << im.name;
    EXPECT_EQ(a.intrinsics().fx, b.intrinsics().fx);
  }
  EXPECT_EQ(got.crs, want.crs);
}

TEST(OrientationExport, ParsesAndNamesFormats) {
  for (const auto f : {OrientationFormat::kAuto, OrientationFormat::kPlain,
                       OrientationFormat::kMetashape, OrientationFormat::kPix4d}) {
    EXPECT_EQ(ParseOrientationFormat(ToString(f)), f);
  }
  EXPECT_THROW(ParseOrientationFormat("agisoft"), Error);
}

TEST(OrientationExport, DetectsTheFormatFromTheFile) {
  EXPECT_EQ(DetectOrientationFormat(Blocks() / "ngi_metashape_opk.txt"),
            OrientationFormat::kMetashape);
  EXPECT_EQ(DetectOrientationFormat(Blocks() / "ngi_calibrated_external_camera_parameters.txt"),
            OrientationFormat::kPix4d);
  EXPECT_EQ(DetectOrientationFormat(Blocks() / "odm_xyz_opk.txt"), OrientationFormat::kPlain);
  // A Pix4D header under another file name, and a Metashape header after a note.
  const fs::path dir = test::ScratchDir();
  WriteText(dir / "poses.txt", "imageName X Y Z Omega Phi Kappa\na 0 0 1 0 0 0\n");
  EXPECT_EQ(DetectOrientationFormat(dir / "poses.txt"), OrientationFormat::kPix4d);
  WriteText(dir / "opk.txt", "# exported by me\n# Cameras (1)\na\t0\t0\t1\t0\t0\t0\n");
  EXPECT_EQ(DetectOrientationFormat(dir / "opk.txt"), OrientationFormat::kMetashape);
  fs::remove_all(dir);
}

TEST(OrientationExport, MetashapeExportOfNgiReadsAsTheNativeBlock) {
  SAPMVS_REQUIRE_PATH(NgiData());
  ExpectSameCameras(ReadBlock(Blocks() / "ngi_metashape.yaml"), ReadBlock(Blocks() / "ngi.yaml"));
}

TEST(OrientationExport, Pix4dExportOfNgiReadsAsTheNativeBlock) {
  SAPMVS_REQUIRE_PATH(NgiData());
  ExpectSameCameras(ReadBlock(Blocks() / "ngi_pix4d.yaml"), ReadBlock(Blocks() / "ngi.yaml"));
}

// The same export with commas (Metashape's other separator), without the
// matrix, and with the matrix but no header: all the same cameras.
TEST(OrientationExport, MetashapeVariantsReadTheSame) {
  SAPMVS_REQUIRE_PATH(NgiData());
  const Block want = ReadBlock(Blocks() / "ngi.yaml");
  const fs::path dir = test::ScratchDir();
  std::string yaml = ReadText(Blocks() / "ngi_metashape.yaml");
  yaml = ReplaceAll(yaml, "../../../shared", (test::SharedDir()).string());
  yaml = ReplaceAll(yaml, "file: ngi_metashape_opk.txt", "file: opk.txt");
  WriteText(dir / "block.yaml", yaml);
  const std::string tabs = ReadText(Blocks() / "ngi_metashape_opk.txt");

  WriteText(dir / "opk.txt", ReplaceAll(tabs, "\t", ", "));
  ExpectSameCameras(ReadBlock(dir / "block.yaml"), want);

  std::string no_matrix;
  std::istringstream in(tabs);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# PhotoID", 0) == 0) {
      line = "# PhotoID, X, Y, Z, Omega, Phi, Kappa";
    } else if (line[0] != '#') {
      size_t at = 0;
      for (int i = 0; i < 7; ++i) at = line.find('\t', at + 1);
      line = line.substr(0, at);
    }
    no_matrix += line + "\n";
  }
  WriteText(dir / "opk.txt", no_matrix);
  ExpectSameCameras(ReadBlock(dir / "block.yaml"), want);

  WriteText(dir / "opk.txt", tabs.substr(tabs.find("33\n") + 3));  // data lines only
  ExpectSameCameras(ReadBlock(dir / "block.yaml"), want);
  fs::remove_all(dir);
}

// Metashape writes r11..r33 as R transposed (world to camera); a matrix
// written the other way round disagrees with the angles and is refused.
TEST(OrientationExport, MetashapeMatrixNotTransposedIsRefused) {
  const fs::path dir = test::ScratchDir();
  const Eigen::Matrix3d r =
      CameraToWorldFromAngles(10, 20, 30, AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  auto row = [](const std::string& name, const Eigen::Matrix3d& m) {
    std::ostringstream s;
    s.precision(17);
    s << name << "\t1\t2\t3\t10\t20\t30";
    for (int i = 0; i < 9; ++i) s << "\t" << m(i / 3, i % 3);
    return s.str() + "\n";
  };
  WriteText(dir / "ok.txt", row("a", r.transpose()));
  const std::vector<ExportedPose> poses = ReadMetashapeOpk(dir / "ok.txt");
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_LT((poses[0].camera_to_world - r).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(poses[0].center, Eigen::Vector3d(1, 2, 3));
  WriteText(dir / "bad.txt", row("a", r));
  test::ExpectInputError([&] { ReadMetashapeOpk(dir / "bad.txt"); }, "bad.txt", 1,
                         "r11 .. r33 disagree with Omega Phi Kappa");
  fs::remove_all(dir);
}

TEST(OrientationExport, ExportNeedsOneCamera) {
  const fs::path dir = test::ScratchDir();
  test::WriteMetashapeFixture(dir);
  WriteText(dir / "block.yaml",
            "ground_height: 0\n"
            "cameras:\n"
            "- {name: one, width: 96, height: 72, focal_mm: 10, pixel_um: 10}\n"
            "- {name: two, width: 96, height: 72, focal_mm: 10, pixel_um: 10}\n"
            "images: images/\n"
            "orientation:\n"
            "  file: cameras.txt\n"
            "  format: metashape\n");
  test::ExpectInputError([&] { ReadBlock(dir / "block.yaml"); }, "block.yaml", 7,
                         "names no camera per image: expected one camera in block.yaml");
  fs::remove_all(dir);
}

using Malformed = test::MalformedText;

class MetashapeMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(MetashapeMalformed, FailsNamingFileAndLine) {
  const fs::path dir = test::ScratchDir();
  WriteText(dir / "opk.txt", GetParam().text);
  test::ExpectInputError([&] { ReadMetashapeOpk(dir / "opk.txt"); }, "opk.txt", GetParam().line,
                         GetParam().expect);
  fs::remove_all(dir);
}

const char kHeader[] =
    "# Cameras (2)\n# PhotoID, X, Y, Z, Omega, Phi, Kappa, r11, r12, r13, r21, r22, r23, r31, "
    "r32, r33\n";
const char kIdentity[] = "\t1\t0\t0\t0\t1\t0\t0\t0\t1\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, MetashapeMalformed,
    ::testing::Values(
        Malformed{"SevenFieldsUnderAMatrixHeader", std::string(kHeader) + "a\t0\t0\t1\t0\t0\t0\n",
                  3, "expected 16 fields (PhotoID, X, Y, Z, Omega, Phi, Kappa, r11 .. r33), got 7"},
        Malformed{"EightFieldsWithoutHeader", "a\t0\t0\t1\t0\t0\t0\t0\n", 1,
                  "expected 7 or 16 fields"},
        Malformed{"NotANumber", std::string(kHeader) + "a\t0\tx\t1\t0\t0\t0" + kIdentity, 3,
                  "expected a number for Y, got 'x'"},
        Malformed{"EmptyField", std::string(kHeader) + "a\t0\t\t1\t0\t0\t0" + kIdentity, 3,
                  "expected a number for Y, got ''"},
        Malformed{"NaNMatrix",
                  std::string(kHeader) + "a\t0\t0\t1\t0\t0\t0\tnan\t0\t0\t0\t1\t0\t0\t0\t1\n", 3,
                  "expected a finite number for r11, got 'nan'"},
        Malformed{"Twice",
                  std::string(kHeader) + "a\t0\t0\t1\t0\t0\t0" + kIdentity +
                      "\na\t1\t0\t1\t0\t0\t0" + kIdentity,
                  5, "image 'a' listed twice (first on line 3)"},
        Malformed{"UnknownHeader", "# PhotoID, Lat, Lon, Alt, Yaw, Pitch, Roll\n", 1,
                  "unknown Metashape header"},
        Malformed{"NoCameras", kHeader, 0, "no cameras in the Metashape export"}),
    [](const auto& p) { return p.param.name; });

class Pix4dMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(Pix4dMalformed, FailsNamingFileAndLine) {
  const fs::path dir = test::ScratchDir();
  WriteText(dir / "p_calibrated_external_camera_parameters.txt", GetParam().text);
  test::ExpectInputError(
      [&] { ReadPix4dExternal(dir / "p_calibrated_external_camera_parameters.txt"); },
      "p_calibrated_external_camera_parameters.txt", GetParam().line, GetParam().expect);
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, Pix4dMalformed,
    ::testing::Values(
        Malformed{"Columns", "imageName X Y Z Omega Phi Kappa\na.JPG 0 0 1 0 0 0 7\n", 2,
                  "expected 7 fields (imageName X Y Z Omega Phi Kappa), got 8"},
        Malformed{"NotANumber", "imageName X Y Z Omega Phi Kappa\na.JPG 0 0 1 0 0 1,5\n", 2,
                  "expected a number for Kappa, got '1,5'"},
        Malformed{"Twice",
                  "imageName X Y Z Omega Phi Kappa\na.JPG 0 0 1 0 0 0\na.JPG 0 0 1 0 0 0\n", 3,
                  "image 'a.JPG' listed twice (first on line 2)"},
        Malformed{"GeographicHeader",
                  "imageName latitude longitude altitude omega phi kappa\na.JPG 47 8 500 0 0 0\n",
                  1, "Pix4D's WGS84 export (latitude, longitude) is not read"},
        Malformed{"OtherHeader", "imageName X Y Z Yaw Pitch Roll\n", 1, "unknown Pix4D header"}),
    [](const auto& p) { return p.param.name; });

// The WGS84 file is refused by its name too, naming the projected file.
TEST(OrientationExport, Pix4dWgs84FileNamesTheProjectedOne) {
  const fs::path dir = test::ScratchDir();
  const fs::path file = dir / "proj_calibrated_external_camera_parameters_wgs84.txt";
  WriteText(file, "a.JPG 47 8 500 0 0 0\n");
  test::ExpectInputError([&] { ReadPix4dExternal(file); }, file.filename().string(), 1,
                         "expected the projected export "
                         "proj_calibrated_external_camera_parameters.txt beside it");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sapmvs

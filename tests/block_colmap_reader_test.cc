#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <iomanip>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// Writes `block` as a COLMAP project: images/ (links) and sparse/0/*.txt, with
// COLMAP's pixel convention (+0.5). No COLMAP model ships with the shared
// data, so the reader is checked on the Herz-Jesu cameras written in it.
fs::path WriteColmap(const Block& block, const fs::path& project) {
  const fs::path model = project / "sparse" / "0";
  fs::create_directories(model);
  fs::create_directories(project / "images");
  std::ofstream cams(model / "cameras.txt"), ims(model / "images.txt");
  cams << "# Camera list with one line of data per camera:\n" << std::setprecision(17);
  ims << "# Image list with two lines of data per image:\n" << std::setprecision(17);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Camera& c = block.images[i].camera;
    const Intrinsics& k = c.intrinsics();
    cams << i + 1 << " PINHOLE " << k.width << " " << k.height << " " << k.fx << " " << k.fy << " "
         << k.cx + 0.5 << " " << k.cy + 0.5 << "\n";
    const Eigen::Quaterniond q(c.rotation());
    const Eigen::Vector3d t = -c.rotation() * c.center();
    ims << i + 1 << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " " << t.x()
        << " " << t.y() << " " << t.z() << " " << i + 1 << " " << block.images[i].name << "\n";
    if (i % 2)
      ims << "\n";  // empty 2D-point lines must be accepted too
    else
      ims << "100.5 200.5 -1 300.5 400.5 -1\n";
    fs::create_symlink(fs::absolute(block.images[i].path),
                       project / "images" / block.images[i].name);
  }
  std::ofstream(model / "points3D.txt") << "# 3D point list\n1 0.5 1.5 2.5 10 20 30 0.4 1 0 2 0\n";
  return project;
}

TEST(ColmapReader, ReadsHerzJesuWrittenAsColmap) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const Block ref = ReadBlock(test::HerzJesu());
  const fs::path project = WriteColmap(ref, test::ScratchDir());
  EXPECT_EQ(DetectBlockFormat(project), BlockFormat::kColmap);
  for (const fs::path& given :
       {project, project / "sparse" / "0", project / "sparse" / "0" / "images.txt"}) {
    const Block block = ReadBlock(given);
    ASSERT_EQ(block.images.size(), ref.images.size());
    ASSERT_EQ(block.sparse_points.size(), 1u);
    EXPECT_LT((block.sparse_points[0] - Eigen::Vector3d(0.5, 1.5, 2.5)).norm(), 1e-12);
    for (size_t i = 0; i < ref.images.size(); ++i) {
      EXPECT_EQ(block.images[i].name, ref.images[i].name);
      const Eigen::Vector3d x = ref.images[i].camera.BackProject({17.5, 2000.25}, 11.0);
      EXPECT_LT((block.images[i].camera.Project(x) - ref.images[i].camera.Project(x)).norm(), 1e-6);
    }
    const auto& matches = test::SiftMatches(ref.images[4].path, ref.images[5].path);
    EXPECT_LT(test::MedianEpipolarDistance(block.images[4].camera, block.images[5].camera, matches),
              1.0);
  }
}

fs::path OneImageProject(const std::string& cameras, const std::string& images) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  std::ofstream(dir / "cameras.txt") << cameras;
  std::ofstream(dir / "images.txt") << images;
  return dir;
}

TEST(ColmapReader, CameraModelsMapToOpenCvIntrinsics) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const fs::path dir = OneImageProject(
      "1 SIMPLE_PINHOLE 3072 2048 2800 1536 1024\n"
      "2 SIMPLE_RADIAL 3072 2048 2800 1536 1024 -0.1\n"
      "3 RADIAL 3072 2048 2800 1536 1024 -0.1 0.02\n"
      "4 OPENCV 3072 2048 2800 2810 1536 1024 -0.1 0.02 0.001 -0.002\n",
      "1 1 0 0 0 0 0 0 1 0000.jpg\n\n2 1 0 0 0 0 0 1 2 0001.jpg\n\n"
      "3 1 0 0 0 0 0 2 3 0002.jpg\n\n4 1 0 0 0 0 0 3 4 0003.jpg\n\n");
  for (const char* name : {"0000.jpg", "0001.jpg", "0002.jpg", "0003.jpg"}) {
    fs::create_symlink(test::HerzJesu() / "images" / name, dir / "images" / name);
  }
  const Block b = ReadBlock(dir);
  ASSERT_EQ(b.images.size(), 4u);
  EXPECT_DOUBLE_EQ(b.images[0].camera.intrinsics().cx, 1535.5);
  EXPECT_DOUBLE_EQ(b.images[0].camera.intrinsics().fy, 2800);
  EXPECT_TRUE(b.images[0].camera.intrinsics().distortion.IsZero());
  EXPECT_DOUBLE_EQ(b.images[1].camera.intrinsics().distortion.k1, -0.1);
  EXPECT_DOUBLE_EQ(b.images[2].camera.intrinsics().distortion.k2, 0.02);
  const Intrinsics& k = b.images[3].camera.intrinsics();
  EXPECT_DOUBLE_EQ(k.fy, 2810);
  EXPECT_DOUBLE_EQ(k.cy, 1023.5);
  EXPECT_DOUBLE_EQ(k.distortion.p1, 0.001);
  EXPECT_DOUBLE_EQ(k.distortion.p2, -0.002);
  EXPECT_LT((b.images[2].camera.center() - Eigen::Vector3d(0, 0, -2)).norm(), 1e-12);
}

struct ColmapMalformed {
  std::string name;
  std::string cameras;
  std::string images;
  std::string file;
  int line;
  std::string expect;
};

// Keeps ctest's discovered test names stable (no byte dumps).
void PrintTo(const ColmapMalformed& m, std::ostream* os) { *os << m.name; }

class ColmapReaderMalformed : public ::testing::TestWithParam<ColmapMalformed> {};

TEST_P(ColmapReaderMalformed, FailsNamingFileAndLine) {
  const ColmapMalformed& m = GetParam();
  const fs::path dir = OneImageProject(m.cameras, m.images);
  test::ExpectInputError([&] { ReadBlock(dir); }, m.file, m.line, m.expect);
}

const char kCam[] = "# comment\n1 PINHOLE 640 480 500 500 320 240\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, ColmapReaderMalformed,
    ::testing::Values(ColmapMalformed{"UnknownModel", "1 FISHEYE_WEIRD 640 480 500 320 240\n", "",
                                      "cameras.txt", 1, "unsupported camera model 'FISHEYE_WEIRD'"},
                      ColmapMalformed{"WrongParamCount", "1 PINHOLE 640 480 500 500 320\n", "",
                                      "cameras.txt", 1, "expected 8 fields"},
                      ColmapMalformed{"BadQuaternion", kCam,
                                      "# images\n1 2 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", 2,
                                      "norm 2"},
                      ColmapMalformed{"UnknownCamera", kCam, "1 1 0 0 0 0 0 0 9 a.jpg\n\n",
                                      "images.txt", 1, "unknown CAMERA_ID 9"},
                      ColmapMalformed{"ShortImageLine", kCam, "1 1 0 0 0 0 0 0 1\n\n", "images.txt",
                                      1, "expected at least 10 fields"},
                      ColmapMalformed{"NotANumber", kCam, "1 1 0 0 0 x 0 0 1 a.jpg\n\n",
                                      "images.txt", 1, "got 'x'"}),
    [](const auto& p) { return p.param.name; });

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>

#include <fstream>
#include <iomanip>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

std::string Name8(size_t i) {
  std::ostringstream s;
  s << std::setw(8) << std::setfill('0') << i;
  return s.str();
}

// Writes `block` as VisualSFM would: txt/NNNNNNNN.txt and visualize/ (links to
// the real images). No real PMVS folder ships with the shared data, so the
// reader is checked on the Herz-Jesu cameras written in its format.
fs::path WritePmvs(const Block& block, const fs::path& dir, double scale) {
  fs::create_directories(dir / "txt");
  fs::create_directories(dir / "visualize");
  for (size_t i = 0; i < block.images.size(); ++i) {
    std::ofstream out(dir / "txt" / (Name8(i) + ".txt"));
    out << "CONTOUR\n" << std::setprecision(17);
    const Eigen::Matrix<double, 3, 4> p = scale * block.images[i].camera.ProjectionMatrix();
    for (int r = 0; r < 3; ++r)
      out << p(r, 0) << " " << p(r, 1) << " " << p(r, 2) << " " << p(r, 3) << "\n";
    fs::create_symlink(fs::absolute(block.images[i].path), dir / "visualize" / (Name8(i) + ".jpg"));
  }
  return dir;
}

TEST(PmvsReader, ReadsHerzJesuWrittenAsPmvs) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const Block ref = ReadBlock(test::HerzJesu());
  // VisualSFM writes P at arbitrary scale; a negative one flips the sign.
  const fs::path dir = WritePmvs(ref, test::ScratchDir(), -1e-3);
  EXPECT_EQ(DetectBlockFormat(dir), BlockFormat::kPmvs);
  const Block block = ReadBlock(dir);
  ASSERT_EQ(block.images.size(), ref.images.size());
  for (size_t i = 0; i < ref.images.size(); ++i) {
    EXPECT_EQ(block.images[i].name, Name8(i));
    EXPECT_EQ(block.images[i].camera.width(), 3072);  // from the image header
    EXPECT_EQ(block.images[i].camera.height(), 2048);
    const Eigen::Vector3d x = ref.images[i].camera.BackProject({2000.5, 300.25}, 9.0);
    EXPECT_LT((block.images[i].camera.Project(x) - ref.images[i].camera.Project(x)).norm(), 1e-6);
    EXPECT_LT((block.images[i].camera.center() - ref.images[i].camera.center()).norm(), 1e-7);
  }
  // The real images still satisfy the epipolar geometry of the read cameras.
  const auto& matches = test::SiftMatches(ref.images[2].path, ref.images[3].path);
  EXPECT_LT(test::MedianEpipolarDistance(block.images[2].camera, block.images[3].camera, matches),
            1.0);
}

using Malformed = test::MalformedText;

class PmvsReaderMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(PmvsReaderMalformed, FailsNamingFileAndLine) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "txt");
  fs::create_directories(dir / "visualize");
  fs::create_symlink(test::HerzJesu() / "images" / "0000.jpg", dir / "visualize" / "00000000.jpg");
  std::ofstream(dir / "txt" / "00000000.txt") << GetParam().text;
  test::ExpectInputError([&] { ReadBlock(dir); }, "00000000.txt", GetParam().line,
                         GetParam().expect);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, PmvsReaderMalformed,
    ::testing::Values(
        Malformed{"NoContour", "1 0 0 0\n0 1 0 0\n0 0 1 0\n", 1,
                  "expected the header line 'CONTOUR'"},
        Malformed{"ShortRow", "CONTOUR\n1 0 0 0\n0 1 0\n0 0 1 0\n", 3, "expected 4 fields"},
        Malformed{"Truncated", "CONTOUR\n1 0 0 0\n0 1 0 0\n", 3, "unexpected end of file"},
        Malformed{"Singular", "CONTOUR\n1 0 0 0\n0 1 0 0\n0 0 0 1\n", 2, "singular"},
        Malformed{"NaN", "CONTOUR\n1 0 0 0\n0 1 0 nan\n0 0 1 0\n", 3, "finite"}),
    [](const auto& p) { return p.param.name; });

TEST(PmvsReader, MissingImageIsReported) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "txt");
  fs::create_directories(dir / "visualize");
  std::ofstream(dir / "txt" / "00000007.txt") << "CONTOUR\n1 0 0 0\n0 1 0 0\n0 0 1 0\n";
  try {
    ReadBlock(dir);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no image 00000007.*"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

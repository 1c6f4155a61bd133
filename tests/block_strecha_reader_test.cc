#include <gtest/gtest.h>

#include <fstream>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

TEST(StrechaReader, ReadsHerzJesuP8) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const Block block = ReadBlock(test::HerzJesu());
  EXPECT_EQ(block.format, "strecha");
  ASSERT_EQ(block.images.size(), 8u);
  for (const BlockImage& im : block.images) {
    EXPECT_EQ(im.camera.width(), 3072);
    EXPECT_EQ(im.camera.height(), 2048);
    EXPECT_NEAR(im.camera.intrinsics().fx, 2759.48, 1e-9);
    EXPECT_NEAR(im.camera.intrinsics().cy, 1006.81, 1e-9);
    EXPECT_TRUE(fs::exists(im.path));
  }
  EXPECT_EQ(block.images[0].name, "0000.jpg");
  // From the file: C of 0000 is (-6.71999, -14.2551, 0.279539); the optical
  // axis is R's third column (0.98958, 0.0534769, -0.133684).
  EXPECT_LT(
      (block.images[0].camera.center() - Eigen::Vector3d(-6.71999, -14.2551, 0.279539)).norm(),
      1e-9);
  EXPECT_LT(
      (block.images[0].camera.ViewingDirection() - Eigen::Vector3d(0.98958, 0.0534769, -0.133684))
          .norm(),
      1e-5);
}

TEST(StrechaReader, SiftMatchesSatisfyTheEpipolarGeometry) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  const Block block = ReadBlock(test::HerzJesu());
  for (size_t i = 0; i + 1 < block.images.size(); ++i) {
    const BlockImage& a = block.images[i];
    const BlockImage& b = block.images[i + 1];
    const auto& matches = test::SiftMatches(a.path, b.path);
    ASSERT_GE(matches.size(), 100u) << a.name << " / " << b.name;
    const double median = test::MedianEpipolarDistance(a.camera, b.camera, matches);
    std::cout << "[ epipolar ] " << a.name << " / " << b.name << ": " << matches.size()
              << " matches, median distance " << median << " px\n";
    EXPECT_LT(median, 1.0);
    // Control: tilting camera b by 0.1 deg about its x axis (across the
    // mostly horizontal epipolar lines) must break it.
    const Camera turned(b.camera.intrinsics(), RotX(0.1 * M_PI / 180) * b.camera.rotation(),
                        b.camera.center());
    EXPECT_GT(test::MedianEpipolarDistance(a.camera, turned, matches), 2.0);
  }
}

using Malformed = test::MalformedText;

class StrechaReaderMalformed : public ::testing::TestWithParam<Malformed> {};

TEST_P(StrechaReaderMalformed, FailsNamingFileAndLine) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  std::ofstream(dir / "images" / "0000.png") << "not read: the reader fails first";
  std::ofstream(dir / "0000.png.camera") << GetParam().text;
  test::ExpectInputError([&] { ReadBlock(dir); }, "0000.png.camera", GetParam().line,
                         GetParam().expect);
}

const char kK[] = "2759.48 0 1520.69\n0 2764.16 1006.81\n0 0 1\n";
const char kR[] =
    "-0.0552 0.132982 0.98958\n0.998433 0.0164966 0.0534769\n-0.00921322 0.990981 -0.133684\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, StrechaReaderMalformed,
    ::testing::Values(
        Malformed{"MissingSize", std::string(kK) + "0 0 0\n" + kR + "-6.7 -14.2 0.27\n", 8,
                  "expected image size W H"},
        Malformed{"NotANumber", std::string(kK) + "0 0 0\n" + kR + "-6.7 abc 0.27\n3072 2048\n", 8,
                  "got 'abc'"},
        Malformed{"NotARotation",
                  std::string(kK) + "0 0 0\n1 0 0\n0 1 0\n0 0 2\n1 2 3\n3072 2048\n", 7,
                  "not a rotation matrix"},
        Malformed{"ShortKRow", "2759.48 0\n0 2764.16 1006.81\n0 0 1\n", 1, "expected 3 fields"},
        Malformed{"BadKBottomRow", "2759.48 0 1520.69\n0 2764.16 1006.81\n0 1 1\n0 0 0\n", 3,
                  "expected K = "}),
    [](const auto& p) { return p.param.name; });

}  // namespace
}  // namespace sapmvs

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "sapmvs/io/las_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

class XyzIoTest : public test::ScratchTest {
 protected:
  fs::path WriteText(const std::string& name, const std::string& text) const {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path;
  }
};

// Expects ReadXyz(path) to fail at `line` with a message containing `expected`.
void ExpectXyzError(const fs::path& path, int line, const std::string& expected) {
  try {
    ReadXyz(path);
    ADD_FAILURE() << "expected an InputError containing '" << expected << "'";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    const std::string prefix = path.string() + ":" + std::to_string(line) + ": ";
    EXPECT_EQ(std::string(e.what()).rfind(prefix, 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

std::vector<PointRecord> RandomPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-1000, 1000);
  std::uniform_int_distribution<int> c(0, 255);
  std::vector<PointRecord> points(n);
  for (PointRecord& p : points) {
    p.x = 5e5 + d(rng);
    p.y = 5.4e6 + d(rng);
    p.z = 300 + d(rng) / 10;
    p.r = ColorTo16(static_cast<uint8_t>(c(rng)));
    p.g = ColorTo16(static_cast<uint8_t>(c(rng)));
    p.b = ColorTo16(static_cast<uint8_t>(c(rng)));
  }
  return points;
}

TEST_F(XyzIoTest, RoundTripWithinThePrecision) {
  const fs::path path = dir_ / "points.xyz";
  const std::vector<PointRecord> points = RandomPoints(93, 21);
  WriteXyz(path, points, 3);
  const XyzCloud cloud = ReadXyz(path);
  EXPECT_FALSE(cloud.has_rgb);
  ASSERT_EQ(cloud.points.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_NEAR(cloud.points[i].x, points[i].x, 0.0005 + 1e-9) << i;
    EXPECT_NEAR(cloud.points[i].y, points[i].y, 0.0005 + 1e-9) << i;
    EXPECT_NEAR(cloud.points[i].z, points[i].z, 0.0005 + 1e-9) << i;
    EXPECT_EQ(cloud.points[i].r, 0) << i;
  }
}

TEST_F(XyzIoTest, RgbRoundTripsAs8BitColour) {
  const fs::path path = dir_ / "rgb.xyz";
  const std::vector<PointRecord> points = RandomPoints(7, 22);
  WriteXyz(path, points, 2, /*rgb=*/true);
  std::ifstream in(path);
  std::string x, y, z;
  int r = -1, g = -1, b = -1;
  in >> x >> y >> z >> r >> g >> b;
  EXPECT_EQ(r, ColorTo8(points[0].r));
  EXPECT_EQ(x.substr(x.find('.')).size(), 3u) << "two decimals: " << x;
  const XyzCloud cloud = ReadXyz(path);
  EXPECT_TRUE(cloud.has_rgb);
  ASSERT_EQ(cloud.points.size(), 7u);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(cloud.points[i].r, points[i].r) << i;
    EXPECT_EQ(cloud.points[i].g, points[i].g) << i;
    EXPECT_EQ(cloud.points[i].b, points[i].b) << i;
  }
}

TEST_F(XyzIoTest, CommasCommentsAndBlankLinesAreAccepted) {
  const fs::path path = WriteText("mixed.xyz", "# x y z\n1,2,3\n\n  4 5 6  \r\n7.5, 8 ,9e1\n");
  const XyzCloud cloud = ReadXyz(path);
  ASSERT_EQ(cloud.points.size(), 3u);
  EXPECT_EQ(cloud.points[2].x, 7.5);
  EXPECT_EQ(cloud.points[2].z, 90);
}

TEST_F(XyzIoTest, MalformedLinesNameFileAndLine) {
  ExpectXyzError(WriteText("short.xyz", "1 2 3\n4 5\n"), 2, "expected 3 fields like line 1, got 2");
  ExpectXyzError(WriteText("four.xyz", "# header\n1 2 3 4\n"), 2, "expected 3 fields (X Y Z) or 6");
  ExpectXyzError(WriteText("word.xyz", "1 2 3\n\n1 two 3\n"), 3, "expected a number for Y");
  ExpectXyzError(WriteText("nan.xyz", "1 2 3\n1 2 nan\n"), 2, "expected a finite number for Z");
  ExpectXyzError(WriteText("colour.xyz", "1 2 3 0 0 0\n1 2 3 10 256 0\n"), 2,
                 "expected 8-bit colour 0-255 for G");
}

TEST_F(XyzIoTest, MissingFileNamesThePath) {
  const fs::path path = dir_ / "missing.xyz";
  try {
    ReadXyz(path);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

TEST_F(XyzIoTest, NonFiniteCoordinatesAreRefusedWithNoFileLeft) {
  std::vector<PointRecord> points = RandomPoints(5, 23);
  points[2].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(WriteXyz(dir_ / "nan.xyz", points), Error);
  EXPECT_TRUE(DirIsEmpty());
  EXPECT_THROW(WriteXyz(dir_ / "bad.xyz", RandomPoints(2, 1), -1), Error);
  EXPECT_TRUE(DirIsEmpty());
}

}  // namespace
}  // namespace sapmvs

#include "match/group_data.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(TriangulationAngleDeg, KnownAngles) {
  const Eigen::Vector3d x(0, 0, 0);
  EXPECT_NEAR(TriangulationAngleDeg({1, 0, 0}, {0, 1, 0}, x), 90.0, 1e-12);
  EXPECT_NEAR(TriangulationAngleDeg({5, 0, 0}, {-7, 0, 0}, x), 180.0, 1e-12);
  EXPECT_NEAR(TriangulationAngleDeg({3, 3, 3}, {1, 1, 1}, x), 0.0, 1e-5);
  EXPECT_NEAR(TriangulationAngleDeg({1, 0, 0}, {1, 1, 0}, x), 45.0, 1e-12);
  // Two cameras 100 up, 2 h tan(15 deg) apart, see the point between them at 30 degrees.
  const double half = 100 * std::tan(15.0 * kPi / 180.0);
  EXPECT_NEAR(TriangulationAngleDeg({512000 - half, 5405000, 400}, {512000 + half, 5405000, 400},
                                    {512000, 5405000, 300}),
              30.0, 1e-9);
}

TEST(TriangulationAngleDeg, SymmetricAndIndependentOfDistanceAlongTheRays) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(-1, 1), scale(0.1, 10);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d x(100 * unit(rng), 100 * unit(rng), 10 * unit(rng));
    const Eigen::Vector3d da = Eigen::Vector3d(unit(rng), unit(rng), 1).normalized();
    const Eigen::Vector3d db = Eigen::Vector3d(unit(rng), unit(rng), 1).normalized();
    const double expected = std::acos(da.dot(db)) * 180.0 / kPi;
    const double got = TriangulationAngleDeg(x + 50 * da, x + 80 * db, x);
    EXPECT_NEAR(got, expected, 1e-9) << "trial " << trial;
    EXPECT_NEAR(TriangulationAngleDeg(x + 80 * db, x + 50 * da, x), got, 1e-12);
    EXPECT_NEAR(TriangulationAngleDeg(x + scale(rng) * da, x + scale(rng) * db, x), got, 1e-9);
  }
}

// A group keeps grey levels only; the colours read again at its end are the
// pixels the grey levels came from, and an image file replaced or removed
// since the load is refused, naming it.
class LoadColorTest : public test::ScratchTest {};

TEST_F(LoadColorTest, ReadsTheLoadedPixelsAgainAndRefusesAChangedFile) {
  namespace fs = std::filesystem;
  fs::copy(test::Simulated("tiny", 1), dir_ / "tiny", fs::copy_options::recursive);
  const Block block = ReadBlock(dir_ / "tiny" / "block.yaml");
  const MatchGroupData group = LoadMatchGroup(block, {0, 1, 2, 3}, 1, nullptr);
  for (const MatchImage& im : group.images) {
    const cv::Mat color = LoadColorAtLevel(block, im, 1);
    ASSERT_EQ(color.type(), CV_8UC3);
    ASSERT_EQ(color.size(), im.grey.size());
    cv::Mat grey8, grey;
    cv::cvtColor(color, grey8, cv::COLOR_BGR2GRAY);
    grey8.convertTo(grey, CV_32F);
    EXPECT_EQ(cv::norm(grey, im.grey, cv::NORM_INF), 0.0) << im.name;
  }
  const fs::path touched = block.images[1].path;
  fs::last_write_time(touched, fs::last_write_time(touched) + std::chrono::seconds(2));
  try {
    LoadColorAtLevel(block, group.images[1], 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(touched.string() + ": image file changed"),
              std::string::npos)
        << e.what();
  }
  fs::remove(block.images[2].path);
  try {
    LoadColorAtLevel(block, group.images[2], 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(block.images[2].path.string()), std::string::npos)
        << e.what();
  }
  EXPECT_NO_THROW(LoadColorAtLevel(block, group.images[0], 1));
}

}  // namespace
}  // namespace sapmvs

#include "device/bilinear_sampler.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "sapmvs/util/kernel_limits.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::ClTest;

class BilinearSamplerTest : public ClTest {};

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kMaxPixel = 100.0f;  // Pixel values lie in [-kMaxPixel, kMaxPixel].

using test::NearAbsRel;

// float32 bilinear interpolation rounds a handful of times on values up to
// kMaxPixel; 4 epsilons of that is about 6x the worst error seen on PoCL and
// leaves room for FMA contraction on other devices.
constexpr double kSampleAbsTol = 4.0 * FLT_EPSILON * kMaxPixel;
constexpr double kSampleRelTol = 4.0 * FLT_EPSILON;

// An image whose padding (beyond width in each row) is NaN, so a read of the
// padding would turn into a NaN mismatch.
struct TestImage {
  std::vector<float> pixels;
  FloatImageView view;
};

TestImage RandomImage(int width, int height, int row_pitch, uint32_t seed) {
  TestImage image;
  image.view.layout = {width, height, row_pitch};
  image.pixels.assign(image.view.layout.RequiredElements(), kNaNf);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(-kMaxPixel, kMaxPixel);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c)
      image.pixels[static_cast<size_t>(r) * row_pitch + c] = value(rng);
  }
  image.view.data = image.pixels.data();
  return image;
}

float NextUp(float v) { return std::nextafter(v, kInf); }
float NextDown(float v) { return std::nextafter(v, -kInf); }

// Random positions around and inside the image, every position on or one ulp
// either side of each border, and non-finite coordinates.
std::vector<Eigen::Vector2f> TestPoints(int width, int height, uint32_t seed) {
  std::mt19937 rng(seed);
  const float w = static_cast<float>(width - 1);
  const float h = static_cast<float>(height - 1);
  std::uniform_real_distribution<float> any_x(-1.5f, w + 1.5f);
  std::uniform_real_distribution<float> any_y(-1.5f, h + 1.5f);
  std::uniform_real_distribution<float> in_x(0.0f, w);
  std::uniform_real_distribution<float> in_y(0.0f, h);
  std::vector<Eigen::Vector2f> points;
  for (int i = 0; i < 2000; ++i) points.emplace_back(any_x(rng), any_y(rng));
  for (int i = 0; i < 2000; ++i) points.emplace_back(in_x(rng), in_y(rng));
  const std::vector<float> border_x = {-0.0f,         0.0f, NextUp(0.0f), NextDown(0.0f), -0.5f,
                                       NextUp(w),     w,    NextDown(w),  w + 0.5f,       w + 1.0f,
                                       NextDown(1.0f)};
  const std::vector<float> border_y = {-0.0f,         0.0f, NextUp(0.0f), NextDown(0.0f), -0.5f,
                                       NextUp(h),     h,    NextDown(h),  h + 0.5f,       h + 1.0f,
                                       NextDown(1.0f)};
  for (float x : border_x) {
    for (float y : border_y) points.emplace_back(x, y);  // Corners.
    for (int i = 0; i < 20; ++i) points.emplace_back(x, in_y(rng));
  }
  for (float y : border_y) {
    for (int i = 0; i < 20; ++i) points.emplace_back(in_x(rng), y);
  }
  for (float bad : {kNaNf, kInf, -kInf}) {
    points.emplace_back(bad, 0.0f);
    points.emplace_back(0.0f, bad);
    points.emplace_back(bad, bad);
  }
  return points;
}

struct SizeCase {
  int width;
  int height;
  int row_pitch;
  uint32_t seed;
};

// Readable names in ctest instead of gtest's byte dump.
void PrintTo(const SizeCase& c, std::ostream* out) {
  *out << c.width << "x" << c.height << " pitch " << c.row_pitch << " seed " << c.seed;
}

std::string CaseName(const ::testing::TestParamInfo<SizeCase>& info) {
  return std::to_string(info.param.width) + "x" + std::to_string(info.param.height) + "_pitch" +
         std::to_string(info.param.row_pitch);
}

class BilinearSamplerSizeTest : public ClTest, public ::testing::WithParamInterface<SizeCase> {};

TEST_P(BilinearSamplerSizeTest, MatchesDoubleReference) {
  const SizeCase& c = GetParam();
  const TestImage image = RandomImage(c.width, c.height, c.row_pitch, c.seed);
  const std::vector<Eigen::Vector2f> points = TestPoints(c.width, c.height, c.seed + 1);
  BilinearSampler sampler(context());
  const std::vector<float> values = sampler.Sample(image.view, points);
  const std::vector<double> expected = BilinearSampleReference(image.view, points);
  ASSERT_EQ(values.size(), points.size());
  int num_nan = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_TRUE(NearAbsRel(values[i], expected[i], kSampleAbsTol, kSampleRelTol))
        << "at (" << points[i].x() << ", " << points[i].y() << "), point " << i;
    num_nan += std::isnan(expected[i]) ? 1 : 0;
  }
  // Both outcomes must actually be exercised.
  EXPECT_GT(num_nan, 0);
  EXPECT_LT(num_nan, static_cast<int>(points.size()));
}

TEST_P(BilinearSamplerSizeTest, PixelCentresReturnThePixelExactly) {
  const SizeCase& c = GetParam();
  const TestImage image = RandomImage(c.width, c.height, c.row_pitch, c.seed);
  std::mt19937 rng(c.seed + 2);
  std::vector<Eigen::Vector2f> points;
  std::vector<float> pixels;
  const size_t num_pixels = static_cast<size_t>(c.width) * c.height;
  for (size_t i = 0; i < std::min<size_t>(num_pixels, 5000); ++i) {
    // All pixels of small images, a random sample (borders included) of large ones.
    const size_t k = num_pixels <= 5000 ? i : rng() % num_pixels;
    const int col = static_cast<int>(k % c.width);
    const int row = static_cast<int>(k / c.width);
    points.emplace_back(static_cast<float>(col), static_cast<float>(row));
    pixels.push_back(image.pixels[static_cast<size_t>(row) * c.row_pitch + col]);
  }
  points.emplace_back(static_cast<float>(c.width - 1), static_cast<float>(c.height - 1));
  pixels.push_back(image.pixels[static_cast<size_t>(c.height - 1) * c.row_pitch + c.width - 1]);

  BilinearSampler sampler(context());
  const std::vector<float> values = sampler.Sample(image.view, points);
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(values[i], pixels[i]) << "at (" << points[i].x() << ", " << points[i].y() << ")";
    EXPECT_EQ(BilinearSampleReference(image.view, points[i].x(), points[i].y()), pixels[i]);
  }
}

INSTANTIATE_TEST_SUITE_P(Sizes, BilinearSamplerSizeTest,
                         ::testing::Values(SizeCase{1, 1, 1, 11}, SizeCase{1, 9, 1, 12},
                                           SizeCase{2, 1, 2, 13}, SizeCase{7, 5, 7, 14},
                                           SizeCase{7, 5, 9, 15}, SizeCase{93, 31, 93, 16},
                                           SizeCase{93, 31, 100, 17}, SizeCase{640, 481, 640, 18}),
                         CaseName);

TEST_F(BilinearSamplerTest, WorkGroupSizeDoesNotChangeResults) {
  const TestImage image = RandomImage(93, 31, 96, 21);
  const std::vector<Eigen::Vector2f> points = TestPoints(93, 31, 22);
  const std::vector<float> reference = BilinearSampler(context()).Sample(image.view, points);
  for (int group : {1, 7, 32, 256}) {
    BilinearSamplerOptions options;
    options.work_group_size = group;
    const std::vector<float> values =
        BilinearSampler(context(), options).Sample(image.view, points);
    ASSERT_EQ(values.size(), reference.size());
    for (size_t i = 0; i < values.size(); ++i) {
      // Same arithmetic per work-item: identical bits, NaN included.
      ASSERT_TRUE(values[i] == reference[i] || (std::isnan(values[i]) && std::isnan(reference[i])))
          << "work-group size " << group << ", point " << i;
    }
  }
}

TEST_F(BilinearSamplerTest, RejectsBadInputBeforeEnqueue) {
  BilinearSampler sampler(context());
  const std::vector<float> pixels(100, 1.0f);
  const std::vector<Eigen::Vector2f> points = {{0.5f, 0.5f}};
  const auto expect_error = [&](const FloatImageView& view, const std::string& text) {
    try {
      sampler.Sample(view, points);
      ADD_FAILURE() << "expected Error containing " << text;
    } catch (const ClError& e) {
      ADD_FAILURE() << "the driver saw the bad input: " << e.what();
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  };
  expect_error({pixels.data(), {0, 5, 5}}, "empty (0x5)");
  expect_error({pixels.data(), {5, -1, 5}}, "empty (5x-1)");
  expect_error({pixels.data(), {10, 10, 9}}, "row pitch 9");
  expect_error({nullptr, {10, 10, 10}}, "no pixel data");
  expect_error({pixels.data(), {kMaxImageSide + 1, 1, kMaxImageSide + 1}}, "exceeds");

  EXPECT_TRUE(sampler.Sample({pixels.data(), {10, 10, 10}}, {}).empty());

  // Device-resident variant: buffers too small for the layout or the batch.
  ClBuffer image(context(), 10 * sizeof(float));
  ClBuffer point_buffer(context(), 2 * sizeof(float));
  ClBuffer values(context(), sizeof(float));
  EXPECT_THROW(sampler.Sample(image, {4, 4, 4}, point_buffer, 1, values), Error);
  EXPECT_THROW(sampler.Sample(image, {5, 2, 5}, point_buffer, 2, values), Error);
  EXPECT_THROW(sampler.Sample(image, {5, 2, 5}, point_buffer, -1, values), Error);
  EXPECT_NO_THROW(sampler.Sample(image, {5, 2, 5}, point_buffer, 1, values).Wait());

  BilinearSamplerOptions options;
  options.work_group_size = 0;
  EXPECT_FALSE(options.Check());
  EXPECT_THROW(BilinearSampler(context(), options), Error);
}

TEST(BilinearReferenceTest, KnownValuesAndBorderPolicy) {
  // 3x2 image, row pitch 4 (padding NaN).
  const std::vector<float> pixels = {0, 1, 2, kNaNf, 10, 11, 12, kNaNf};
  const FloatImageView image{pixels.data(), {3, 2, 4}};
  EXPECT_DOUBLE_EQ(BilinearSampleReference(image, 0.5, 0.5), 5.5);
  EXPECT_DOUBLE_EQ(BilinearSampleReference(image, 1.25, 0.0), 1.25);
  EXPECT_DOUBLE_EQ(BilinearSampleReference(image, 2.0, 1.0), 12.0);  // Last pixel centre.
  EXPECT_DOUBLE_EQ(BilinearSampleReference(image, 2.0, 0.5), 7.0);   // Right border.
  EXPECT_DOUBLE_EQ(BilinearSampleReference(image, -0.0, 0.0), 0.0);
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{-1e-9, 0.0},
                                                                   {0.0, -1e-9},
                                                                   {2.0 + 1e-9, 0.0},
                                                                   {0.0, 1.0 + 1e-9},
                                                                   {-0.5, 0.5},
                                                                   {std::nan(""), 0.0},
                                                                   {INFINITY, 0.0}}) {
    EXPECT_TRUE(std::isnan(BilinearSampleReference(image, x, y))) << x << ", " << y;
  }
  const float single = 42.0f;
  EXPECT_EQ(BilinearSampleReference({&single, {1, 1, 1}}, 0.0, 0.0), 42.0);
  EXPECT_TRUE(std::isnan(BilinearSampleReference({&single, {1, 1, 1}}, 0.25, 0.0)));
  EXPECT_THROW(BilinearSampleReference({&single, {0, 1, 1}}, 0.0, 0.0), Error);
}

}  // namespace
}  // namespace sapmvs

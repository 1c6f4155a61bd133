#include "util/streamed_median.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace sapmvs {
namespace {

// What the filter computed before: the non-NaN values gathered, and
// nth_element at m / 2.
float Stored(const std::vector<float>& values) {
  std::vector<float> d;
  for (const float v : values) {
    if (!std::isnan(v)) d.push_back(v);
  }
  if (d.empty()) return std::nanf("");
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// The values in rows of k, as the filter hands them (a point's k
// neighbours), the last row padded with NaN, which does not count.
float Streamed(const std::vector<float>& values, int k = 1) {
  const size_t rows = (values.size() + k - 1) / k;
  return StreamedMedianOfRows(rows, k, [&](size_t r, float* out) {
    for (int j = 0; j < k; ++j) {
      const size_t i = r * k + j;
      out[j] = i < values.size() ? values[i] : std::nanf("");
    }
  });
}

TEST(StreamedMedian, EqualsTheStoredSelectionOnOddAndEvenCounts) {
  std::mt19937 rng(7);
  std::lognormal_distribution<float> spread(-1.5f, 1.2f);
  std::uniform_real_distribution<float> unit(0, 1);
  for (const size_t n : {1u, 2u, 3u, 17u, 256u, 1001u, 65536u, 100003u}) {
    std::vector<float> v(n);
    for (float& x : v) x = unit(rng) < 0.3f ? std::nanf("") : spread(rng);
    const float want = Stored(v);
    for (const int k : {1, 16}) {
      const float got = Streamed(v, k);
      if (std::isnan(want)) {
        EXPECT_TRUE(std::isnan(got)) << n << " values, all NaN, rows of " << k;
      } else {
        EXPECT_EQ(got, want) << n << " values, rows of " << k;
      }
    }
  }
}

TEST(StreamedMedian, ValuesInOneBinTiesZerosAndInfinity) {
  // All within one histogram bin (they share their top 16 bits).
  std::vector<float> close;
  for (int i = 0; i < 999; ++i) close.push_back(1.0f + static_cast<float>(i % 37) * 1e-6f);
  EXPECT_EQ(Streamed(close), Stored(close));
  // Ties across the median, zeros and an infinite distance (a footprint of 0).
  const std::vector<float> ties = {
      0.f, 0.f, 2.f, 2.f, 2.f, 5.f, std::numeric_limits<float>::infinity()};
  EXPECT_EQ(Streamed(ties), 2.f);
  const std::vector<float> zeros = {0.f, 0.f, 0.f, std::nanf("")};
  EXPECT_EQ(Streamed(zeros), 0.f);
  // The median is the upper one of an even count, as nth_element at m / 2.
  EXPECT_EQ(Streamed({1.f, 4.f, 3.f, 2.f}), 3.f);
}

TEST(StreamedMedian, NaNWhenNothingIsCounted) {
  EXPECT_TRUE(std::isnan(Streamed({})));
  EXPECT_TRUE(std::isnan(Streamed({std::nanf(""), std::nanf("")})));
}

}  // namespace
}  // namespace sapmvs

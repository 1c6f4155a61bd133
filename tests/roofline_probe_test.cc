#include "device/roofline_probe.h"

#include <gtest/gtest.h>

#include <random>

#include "cl_test_fixture.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

class RooflineProbeTest : public test::ClTest {};

std::vector<float> RandomImage(int width, int height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 255.0f);
  std::vector<float> image(static_cast<size_t>(width) * height);
  for (float& p : image) p = u(rng);
  return image;
}

TEST_F(RooflineProbeTest, NccWindowsMatchTheDoubleReference) {
  // Odd sizes, windows against every border, windows partly outside, and a
  // flat region (NaN by the variance rule).
  constexpr int kWidth = 37, kHeight = 23;
  std::vector<float> a = RandomImage(kWidth, kHeight, 11), b = RandomImage(kWidth, kHeight, 12);
  for (int r = 0; r < 12; ++r)
    for (int c = 0; c < 12; ++c) a[static_cast<size_t>(r) * kWidth + c] = 50.0f;  // flat corner
  // b correlated with a where it is a shifted copy: NCC near 1 there.
  for (int r = 0; r < kHeight; ++r)
    for (int c = 0; c + 2 < kWidth; ++c)
      b[static_cast<size_t>(r) * kWidth + c] =
          0.5f * a[static_cast<size_t>(r) * kWidth + c + 2] + 7;
  const FloatImageView va{a.data(), {kWidth, kHeight, kWidth}};
  const FloatImageView vb{b.data(), {kWidth, kHeight, kWidth}};
  for (const int mu : {3, 7, 11}) {
    RooflineProbeOptions o;
    o.patch_size = mu;
    RooflineProbe probe(context(), o);
    std::mt19937 rng(5 + mu);
    std::uniform_int_distribution<int> x(-2, kWidth - mu + 2), y(-2, kHeight - mu + 2);
    std::vector<cl_int4> corners;
    for (int i = 0; i < 997; ++i) corners.push_back({{x(rng), y(rng), x(rng), y(rng)}});
    corners.push_back({{0, 0, 0, 0}});                         // flat in a: NaN
    corners.push_back({{kWidth - mu, kHeight - mu, 20, 10}});  // last valid corner
    corners.push_back({{kWidth - mu + 1, 0, 0, 0}});           // one past: NaN
    corners.push_back({{12, 5, 10, 5}});                       // b = a shifted by 2
    const std::vector<float> got = probe.NccWindows(va, vb, corners);
    ASSERT_EQ(got.size(), corners.size());
    long valid = 0;
    for (size_t i = 0; i < corners.size(); ++i) {
      const double want = NccWindowReference(va, vb, corners[i], mu);
      ASSERT_TRUE(test::NearAbsRel(got[i], want, 2e-5, 1e-4)) << "mu " << mu << " corner " << i;
      valid += !std::isnan(want);
    }
    EXPECT_GT(valid, 300);
    EXPECT_TRUE(std::isnan(got[corners.size() - 4]));
    EXPECT_FALSE(std::isnan(got[corners.size() - 3]));
    EXPECT_TRUE(std::isnan(got[corners.size() - 2]));
    EXPECT_NEAR(got.back(), 1.0, 1e-5);
  }
}

TEST_F(RooflineProbeTest, CopyCopiesOddCountsExactly) {
  const int n = 1001;
  std::vector<cl_float4> src(n), dst(n);
  for (int i = 0; i < n; ++i) src[i] = {{1.0f * i, -1.0f * i, 0.5f * i, 3.0f}};
  ClBuffer s(context(), n * sizeof(cl_float4)), d(context(), (n + 3) * sizeof(cl_float4));
  std::vector<cl_float4> sentinel(n + 3, cl_float4{{-7, -7, -7, -7}});
  d.WriteVector(sentinel);
  s.WriteVector(src);
  RooflineProbe probe(context());
  probe.Copy(s, d, n).Wait();
  std::vector<cl_float4> out(n + 3);
  d.ReadVector(&out);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 4; ++k) ASSERT_EQ(out[i].s[k], src[i].s[k]) << i;
  for (int i = n; i < n + 3; ++i) EXPECT_EQ(out[i].s[0], -7.0f);  // nothing past n
  EXPECT_THROW(probe.Copy(s, d, n + 1), Error);
}

TEST(RooflineProbeOptions, BadOptionsNameTheValue) {
  RooflineProbeOptions o;
  EXPECT_EQ(o.Problem(), "");
  o.patch_size = 4;
  EXPECT_NE(o.Problem().find("patch_size = 4"), std::string::npos);
  o.patch_size = 7;
  o.work_group_size = 0;
  EXPECT_NE(o.Problem().find("work_group_size = 0"), std::string::npos);
}

}  // namespace
}  // namespace sapmvs

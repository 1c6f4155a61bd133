#include "sapmvs/run/seam_leveling.h"

#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Two groups' ground centres 10 apart along x at UTM-sized coordinates: the
// border between their cores is x = x0.
constexpr double kSeamX0 = 500000.0, kSeamY0 = 5400000.0;
const std::vector<Eigen::Vector2d> kSeamCenters = {{kSeamX0 - 5, kSeamY0}, {kSeamX0 + 5, kSeamY0}};

SeamOptions SeamTestOptions() {
  SeamOptions o;
  o.cell = 0.2;
  o.band = 0.5;
  o.feather = 2;
  o.max_offset = 0.1;
  return o;
}

// Points every 0.05 of group g over x in [x0 + from, x0 + to), y in
// [y0 - 3, y0 + 3), at height z(x, y) plus noise of 5 mm.
void AddGroup(SeamLeveling* s, int g, double from, double to,
              const std::function<double(double, double)>& z) {
  std::mt19937 rng(g + 1);
  std::normal_distribution<double> noise(0, 0.005);
  for (double x = from; x < to; x += 0.05) {
    for (double y = -3; y < 3; y += 0.05) {
      s->Add(g, {kSeamX0 + x, kSeamY0 + y, z(x, y) + noise(rng)});
    }
  }
}

TEST(SeamLeveling, SplitsTheStepBetweenTheGroupsAndFadesItOut) {
  // Group 1 places the ground 6 cm higher; each matched 0.4 beyond its core.
  SeamLeveling s(kSeamCenters, SeamTestOptions());
  AddGroup(&s, 0, -8, 0.4, [](double, double) { return 100.0; });
  AddGroup(&s, 1, -0.4, 8, [](double, double) { return 100.06; });
  s.Finish();
  EXPECT_EQ(s.pairs(), 1);
  EXPECT_NEAR(s.median_offset(), 0.06, 0.005);
  const double y = kSeamY0 + 1;
  // At the border both move half the step towards each other and meet.
  EXPECT_NEAR(s.Correction(0, {kSeamX0, y, 100.0}), 0.03, 0.003);
  EXPECT_NEAR(s.Correction(1, {kSeamX0, y, 100.06}), -0.03, 0.003);
  // Halfway through the feather, half of that; beyond it, nothing.
  EXPECT_NEAR(s.Correction(0, {kSeamX0 - 1, y, 100.0}), 0.015, 0.002);
  EXPECT_NEAR(s.Correction(1, {kSeamX0 + 1, y, 100.06}), -0.015, 0.002);
  EXPECT_EQ(s.Correction(0, {kSeamX0 - 2.5, y, 100.0}), 0);
  EXPECT_EQ(s.Correction(1, {kSeamX0 + 2.5, y, 100.06}), 0);
  // A point of group 0 on group 1's side (filling its hole) moves by half.
  EXPECT_NEAR(s.Correction(0, {kSeamX0 + 1, y, 100.0}), 0.03, 0.003);
}

TEST(SeamLeveling, EachStretchOfABorderHasItsOwnOffset) {
  // The other group is 4 cm higher in the south, 3 cm lower in the north.
  SeamLeveling s(kSeamCenters, SeamTestOptions());
  AddGroup(&s, 0, -8, 0.4, [](double, double) { return 50.0; });
  AddGroup(&s, 1, -0.4, 8, [](double, double y) { return y < 0 ? 50.04 : 49.97; });
  s.Finish();
  EXPECT_NEAR(s.Correction(0, {kSeamX0, kSeamY0 - 1, 50}), 0.02, 0.003);
  EXPECT_NEAR(s.Correction(0, {kSeamX0, kSeamY0 + 1, 50}), -0.015, 0.003);
}

TEST(SeamLeveling, EachCellOfTheBandMeetsTheOtherGroupsSurface) {
  // Group 1 places a hedge 4 cm higher along 0.6 of the border, 3 of the
  // 10 rows of cells of its stretch, whose median offset is then none.
  SeamLeveling s(kSeamCenters, SeamTestOptions());
  AddGroup(&s, 0, -8, 0.4, [](double, double) { return 20.0; });
  AddGroup(&s, 1, -0.4, 8, [](double, double y) { return y >= 0 && y < 0.6 ? 20.04 : 20.0; });
  s.Finish();
  // At the border the two meet halfway; across the band (0.5) it fades out.
  EXPECT_NEAR(s.Correction(0, {kSeamX0, kSeamY0 + 0.3, 20.0}), 0.02, 0.003);
  EXPECT_NEAR(s.Correction(1, {kSeamX0, kSeamY0 + 0.3, 20.04}), -0.02, 0.003);
  EXPECT_NEAR(s.Correction(0, {kSeamX0 - 0.3, kSeamY0 + 0.3, 20.0}), 0.008, 0.002);
  // Beyond the band only the stretch's own (none) is left, as beside it.
  EXPECT_DOUBLE_EQ(s.Correction(0, {kSeamX0 - 0.6, kSeamY0 + 0.3, 20.0}),
                   s.Correction(0, {kSeamX0 - 0.6, kSeamY0 + 1.5, 20.0}));
  // Beside the hedge nothing moves.
  EXPECT_NEAR(s.Correction(0, {kSeamX0, kSeamY0 + 1.5, 20.0}), 0, 0.003);
}

TEST(SeamLeveling, OffsetsBeyondTheLargestAreSurfacesNotOrientations) {
  // A roof 3 m high on group 1's side of the south half: its band there
  // compares the roof with group 0's ground, and is left alone.
  SeamLeveling s(kSeamCenters, SeamTestOptions());
  AddGroup(&s, 0, -8, 0.4, [](double, double) { return 50.0; });
  AddGroup(&s, 1, -0.4, 8, [](double, double y) { return y < 0 ? 53.0 : 50.04; });
  s.Finish();
  EXPECT_EQ(s.Correction(0, {kSeamX0, kSeamY0 - 1, 50}), 0);
  EXPECT_NEAR(s.Correction(0, {kSeamX0, kSeamY0 + 1, 50}), 0.02, 0.003);
  EXPECT_NEAR(s.median_offset(), 0.04, 0.005);
}

TEST(SeamLeveling, GroupsThatNeverMetAreLeftAlone) {
  // Each matched only its own core: nothing to compare, nothing moved.
  SeamLeveling s(kSeamCenters, SeamTestOptions());
  AddGroup(&s, 0, -8, -0.1, [](double, double) { return 100.0; });
  AddGroup(&s, 1, 0, 8, [](double, double) { return 100.5; });
  s.Finish();
  EXPECT_EQ(s.pairs(), 0);
  EXPECT_EQ(s.Correction(0, {kSeamX0, kSeamY0, 100}), 0);
  EXPECT_EQ(s.Correction(1, {kSeamX0, kSeamY0, 100.5}), 0);
}

TEST(SeamLeveling, RefusesBadOptions) {
  for (const double bad : {0.0, -1.0, std::nan("")}) {
    SeamOptions o = SeamTestOptions();
    o.cell = bad;
    EXPECT_THROW(SeamLeveling(kSeamCenters, o), Error) << bad;
    o = SeamTestOptions();
    o.band = bad;
    EXPECT_THROW(SeamLeveling(kSeamCenters, o), Error) << bad;
    o = SeamTestOptions();
    o.feather = bad;
    EXPECT_THROW(SeamLeveling(kSeamCenters, o), Error) << bad;
    o = SeamTestOptions();
    o.max_offset = bad;
    EXPECT_THROW(SeamLeveling(kSeamCenters, o), Error) << bad;
  }
}

}  // namespace
}  // namespace sapmvs

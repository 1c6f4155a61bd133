#include "match/point_neighbours.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// The definition, by a scan of every pair: the k nearest others within the
// point's radius, distances summed in float in x, y, z order, ties by index.
std::vector<int32_t> ScanAll(const std::vector<float>& xyz, const std::vector<double>& radius,
                             int k) {
  const size_t n = radius.size();
  std::vector<int32_t> out(n * k, -1);
  for (size_t a = 0; a < n; ++a) {
    const float r2 = static_cast<float>(radius[a] * radius[a]);
    std::vector<std::pair<float, int32_t>> near;
    for (size_t b = 0; b < n; ++b) {
      if (b == a) continue;
      float d2 = 0;
      for (int c = 0; c < 3; ++c) {
        const float d = xyz[3 * a + c] - xyz[3 * b + c];
        d2 += d * d;
      }
      if (d2 <= r2) near.emplace_back(d2, static_cast<int32_t>(b));
    }
    std::sort(near.begin(), near.end());
    for (size_t j = 0; j < near.size() && j < static_cast<size_t>(k); ++j) {
      out[a * k + j] = near[j].second;
    }
  }
  return out;
}

void ExpectSameAsScan(const std::vector<float>& xyz, const std::vector<double>& radius, int k) {
  const auto got = NearestWithin(xyz, radius, k);
  const std::vector<int32_t> want = ScanAll(xyz, radius, k);
  ASSERT_EQ(got.size(), want.size());
  long differ = 0;
  for (size_t i = 0; i < got.size(); ++i) differ += got[i] != want[i];
  EXPECT_EQ(differ, 0) << "of " << got.size() << " slots (" << radius.size() << " points, k = " << k
                       << ")";
}

// Layers of points over a rough surface, as overlapping patches emit them,
// with radii that vary per point as slope footprints do.
TEST(NearestWithin, FindsWhatAScanOfEveryPairFinds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  for (const int n : {1, 2, 17, 333, 2501}) {
    std::vector<float> xyz;
    std::vector<double> radius;
    const float side = std::sqrt(static_cast<float>(n)) * 0.7f;
    for (int i = 0; i < n; ++i) {
      const float x = u(rng) * side, y = u(rng) * side;
      xyz.insert(xyz.end(), {x + 1000.f, y - 500.f, 0.2f * std::sin(x) + 0.05f * u(rng) + 80.f});
      radius.push_back(0.5 + 3.0 * u(rng));
    }
    for (const int k : {1, 5, 16}) ExpectSameAsScan(xyz, radius, k);
  }
}

// In the grid's order: every point has a row, and a row holds its point's
// neighbours of the scan, in the scan's order, as rows.
TEST(NearestWithin, RowsInTheGridsOrderHoldTheScansNeighbours) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  const int n = 1201, k = 16;
  std::vector<float> xyz;
  std::vector<double> radius;
  for (int i = 0; i < n; ++i) {
    const float x = u(rng) * 25, y = u(rng) * 25;
    xyz.insert(xyz.end(), {x - 300.f, y + 40.f, 0.3f * std::cos(y) + 0.05f * u(rng)});
    radius.push_back(0.5 + 2.0 * u(rng));
  }
  std::vector<int32_t> order;
  const auto got = NearestWithin(xyz, radius, k, &order);
  const std::vector<int32_t> want = ScanAll(xyz, radius, k);
  ASSERT_EQ(order.size(), static_cast<size_t>(n));
  std::vector<int32_t> row_of(n, -1);
  for (int r = 0; r < n; ++r) {
    ASSERT_GE(order[r], 0);
    ASSERT_LT(order[r], n);
    ASSERT_EQ(row_of[order[r]], -1) << "point " << order[r] << " has two rows";
    row_of[order[r]] = r;
  }
  long differ = 0, rows_moved = 0;
  for (int r = 0; r < n; ++r) {
    rows_moved += order[r] != r;
    for (int j = 0; j < k; ++j) {
      const int32_t b = want[static_cast<size_t>(order[r]) * k + j];
      differ += got[static_cast<size_t>(r) * k + j] != (b < 0 ? -1 : row_of[b]);
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(rows_moved, n / 2);  // the grid's order is not the input's
}

// Equal distances (a lattice, and points repeated at one place) are ordered
// by index; a radius exactly at a lattice distance keeps that neighbour; a
// radius of 0 keeps only repeats.
TEST(NearestWithin, TiesGoByIndexAndTheRadiusIsInclusive) {
  std::vector<float> xyz;
  std::vector<double> radius;
  for (int y = 0; y < 9; ++y) {
    for (int x = 0; x < 11; ++x) {
      xyz.insert(xyz.end(), {static_cast<float>(x), static_cast<float>(y), 3.f});
      radius.push_back((x + y) % 3 == 0 ? 1.0 : (x + y) % 3 == 1 ? 2.0 : 0.0);
    }
  }
  for (int rep = 0; rep < 3; ++rep) {
    xyz.insert(xyz.end(), {4.f, 4.f, 3.f});
    radius.push_back(rep == 0 ? 0.0 : 1.5);
  }
  for (const int k : {1, 4, 9}) ExpectSameAsScan(xyz, radius, k);
  const auto nn = NearestWithin(xyz, radius, 4);
  // (0, 0), radius 1: (1, 0) and (0, 1) at distance 1, the smaller index first.
  EXPECT_EQ(nn[0], 1);
  EXPECT_EQ(nn[1], 11);
  EXPECT_EQ(nn[2], -1);
  // (4, 4), radius 0: only the three points repeated at its place.
  EXPECT_EQ(std::vector<int32_t>(nn.begin() + 48 * 4, nn.begin() + 49 * 4),
            (std::vector<int32_t>{99, 100, 101, -1}));
}

// Clouds the grid's shape must not trip on: a vertical wall (its column
// along x), a line, one place, and two clusters far apart, whose bounding
// box would ask for far more columns than points.
TEST(NearestWithin, WallsLinesOnePlaceAndFarClusters) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> wall, line, place, far;
  for (int i = 0; i < 400; ++i) {
    wall.insert(wall.end(), {5.f + 0.01f * u(rng), 20 * u(rng), 10 * u(rng)});
    line.insert(line.end(), {static_cast<float>(i) * 0.5f, 0.f, 0.f});
    place.insert(place.end(), {1.f, 2.f, 3.f});
    const float off = i % 2 ? 1e5f : 0.f;
    far.insert(far.end(), {off + 3 * u(rng), off + 3 * u(rng), u(rng)});
  }
  const std::vector<double> radius(400, 1.3);
  for (const auto* xyz : {&wall, &line, &place, &far}) ExpectSameAsScan(*xyz, radius, 7);
}

TEST(NearestWithin, RefusesMismatchedSizesAndBadRadii) {
  EXPECT_THROW(NearestWithin({1, 2, 3, 4}, {1.0}, 4), Error);
  EXPECT_THROW(NearestWithin({1, 2, 3}, {1.0}, 0), Error);
  EXPECT_THROW(NearestWithin({1, 2, 3}, {-1.0}, 4), Error);
  EXPECT_THROW(NearestWithin({1, 2, 3}, {std::nan("")}, 4), Error);
  EXPECT_TRUE(NearestWithin({}, {}, 4).empty());
}

// NearestOther against the scan with an unbounded radius, on clouds whose
// nearest neighbours lie from a fraction of the mean spacing to far beyond
// it: isolated points, two clusters 10^5 apart, a wall, a line, one place.
TEST(NearestOther, FindsTheScansNearestAtAnyDistance) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<std::vector<float>> clouds(6);
  for (int i = 0; i < 700; ++i) {
    const float x = u(rng) * 20, y = u(rng) * 20;
    clouds[0].insert(clouds[0].end(), {x + 1000.f, y - 500.f, 0.3f * std::sin(x) + 80.f});
    const float off = i % 2 ? 1e5f : 0.f;
    clouds[1].insert(clouds[1].end(), {off + 3 * u(rng), off + 3 * u(rng), u(rng)});
    clouds[2].insert(clouds[2].end(), {5.f + 0.01f * u(rng), 20 * u(rng), 10 * u(rng)});
    clouds[3].insert(clouds[3].end(), {static_cast<float>(i) * 0.5f, 0.f, 0.f});
    clouds[4].insert(clouds[4].end(), {1.f, 2.f, 3.f});
  }
  // A dense patch and a few points scattered far around it.
  for (int i = 0; i < 500; ++i) clouds[5].insert(clouds[5].end(), {u(rng), u(rng), 0.f});
  for (int i = 0; i < 9; ++i) {
    clouds[5].insert(clouds[5].end(), {400 * u(rng) - 200, 400 * u(rng) - 200, 50 * u(rng)});
  }
  for (const std::vector<float>& xyz : clouds) {
    const size_t n = xyz.size() / 3;
    std::vector<size_t> queries;
    for (size_t a = 0; a < n; a += 3) queries.push_back(a);
    queries.push_back(n - 1);
    const std::vector<int32_t> got = NearestOther(xyz, queries);
    const std::vector<int32_t> want = ScanAll(xyz, std::vector<double>(n, 1e7), 1);
    ASSERT_EQ(got.size(), queries.size());
    long differ = 0;
    for (size_t q = 0; q < queries.size(); ++q) differ += got[q] != want[queries[q]];
    EXPECT_EQ(differ, 0) << "of " << queries.size() << " queries, " << n << " points";
  }
}

TEST(NearestOther, OnePointHasNoneAndBadInputIsRefused) {
  EXPECT_EQ(NearestOther({1, 2, 3}, {0}), (std::vector<int32_t>{-1}));
  EXPECT_TRUE(NearestOther({}, {}).empty());
  EXPECT_THROW(NearestOther({1, 2, 3, 4}, {0}), Error);
  EXPECT_THROW(NearestOther({1, 2, 3, 4, 5, 6}, {2}), Error);
}

}  // namespace
}  // namespace sapmvs

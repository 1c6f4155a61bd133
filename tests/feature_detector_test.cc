#include "match/feature_detector.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <vector>

namespace sapmvs {
namespace {

// Odd sizes, so that the last 32 x 32 blocks are partial.
constexpr int kWidth = 97;
constexpr int kHeight = 71;
constexpr float kBackground = 50.0f;

// A bright axis-aligned square covering pixels [x0, x0 + size) x [y0, y0 + size).
struct Square {
  int x0, y0, size;
  float value;
  // Its corners, on the pixel boundaries.
  std::vector<Eigen::Vector2d> Corners() const {
    const double a = x0 - 0.5, b = x0 + size - 0.5, c = y0 - 0.5, d = y0 + size - 0.5;
    return {{a, c}, {b, c}, {a, d}, {b, d}};
  }
  // Chebyshev distance of pixel (x, y) to the square's outline, measured on
  // the boundary between pixels (0.5 for the rings just inside and outside).
  double OutlineDistance(double x, double y) const {
    const double a = x0 - 0.5, b = x0 + size - 0.5, c = y0 - 0.5, d = y0 + size - 0.5;
    const double dx = std::max({a - x, x - b, 0.0});
    const double dy = std::max({c - y, y - d, 0.0});
    if (dx > 0 || dy > 0) return std::max(dx, dy);  // outside
    return std::min({x - a, b - x, y - c, d - y});  // inside
  }
};

const std::vector<Square>& Squares() {
  static const std::vector<Square> squares = {
      {10, 9, 16, 200.0f}, {52, 12, 21, 180.0f}, {29, 41, 18, 220.0f}, {71, 47, 13, 160.0f}};
  return squares;
}

cv::Mat SquaresImage() {
  cv::Mat grey(kHeight, kWidth, CV_32F, cv::Scalar(kBackground));
  for (const Square& s : Squares()) {
    grey(cv::Rect(s.x0, s.y0, s.size, s.size)).setTo(cv::Scalar(s.value));
  }
  return grey;
}

// A checkerboard of `cell` px squares reaching the image border: many corners
// per 32 x 32 block.
cv::Mat Checkerboard(int cell) {
  cv::Mat grey(kHeight, kWidth, CV_32F);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      grey.at<float>(y, x) = ((x / cell + y / cell) % 2 == 0) ? 40.0f : 210.0f;
    }
  }
  return grey;
}

double DistanceToOutlines(const Eigen::Vector2d& uv) {
  double best = 1e9;
  for (const Square& s : Squares()) best = std::min(best, s.OutlineDistance(uv.x(), uv.y()));
  return best;
}

double DistanceToCorners(const Eigen::Vector2d& uv) {
  double best = 1e9;
  for (const Square& s : Squares()) {
    for (const Eigen::Vector2d& c : s.Corners()) best = std::min(best, (uv - c).norm());
  }
  return best;
}

std::vector<Feature> OfKind(const std::vector<Feature>& features, FeatureKind kind) {
  std::vector<Feature> out;
  for (const Feature& f : features) {
    if (f.kind == kind) out.push_back(f);
  }
  return out;
}

TEST(DetectFeatures, HarrisFindsEverySquareCornerAndNothingElse) {
  // Up to 5 corners share a 32 x 32 block here: a limit that keeps them all.
  const std::vector<Feature> features = DetectFeatures(SquaresImage(), 16, 2);
  const std::vector<Feature> harris = OfKind(features, FeatureKind::kHarris);
  ASSERT_FALSE(harris.empty());
  // Every corner has a Harris feature within 1.5 px ...
  for (const Square& s : Squares()) {
    for (const Eigen::Vector2d& corner : s.Corners()) {
      double nearest = 1e9;
      for (const Feature& f : harris) nearest = std::min(nearest, (f.uv - corner).norm());
      EXPECT_LE(nearest, 1.5) << "corner (" << corner.transpose() << ")";
    }
  }
  // ... and every Harris feature is at a corner.
  for (const Feature& f : harris) {
    EXPECT_LE(DistanceToCorners(f.uv), 1.5) << "Harris feature at (" << f.uv.transpose() << ")";
    EXPECT_GT(f.strength, 0.0f);
  }
}

TEST(DetectFeatures, NoFeatureOfEitherKindInFlatAreas) {
  const std::vector<Feature> features = DetectFeatures(SquaresImage(), 1000, 2);
  ASSERT_FALSE(OfKind(features, FeatureKind::kDog).empty());
  for (const Feature& f : features) {
    // The DoG's sigma-1.6 Gaussian reaches about 5 px; beyond 6 px of every
    // outline the image is flat.
    EXPECT_LE(DistanceToOutlines(f.uv), 6.0)
        << (f.kind == FeatureKind::kHarris ? "Harris" : "DoG") << " feature in a flat area at ("
        << f.uv.transpose() << ")";
  }
}

TEST(DetectFeatures, PixelCoordinatesAreIntegerPixelCentres) {
  for (const Feature& f : DetectFeatures(SquaresImage(), 4, 0)) {
    EXPECT_EQ(f.uv.x(), std::round(f.uv.x()));
    EXPECT_EQ(f.uv.y(), std::round(f.uv.y()));
    EXPECT_GE(f.uv.x(), 0);
    EXPECT_GE(f.uv.y(), 0);
    EXPECT_LE(f.uv.x(), kWidth - 1);
    EXPECT_LE(f.uv.y(), kHeight - 1);
  }
}

// Features per (detector, 32 x 32 block).
std::map<std::tuple<int, int, int>, int> CountPerBlock(const std::vector<Feature>& features) {
  std::map<std::tuple<int, int, int>, int> count;
  for (const Feature& f : features) {
    ++count[{static_cast<int>(f.kind), static_cast<int>(f.uv.x()) / kFeatureBlock,
             static_cast<int>(f.uv.y()) / kFeatureBlock}];
  }
  return count;
}

TEST(DetectFeatures, AtMostPerBlockFeaturesPerDetectorPerBlock) {
  const cv::Mat grey = Checkerboard(6);
  // Unlimited, a block holds many more corners than the limit below ...
  int most_unlimited = 0;
  for (const auto& [key, n] : CountPerBlock(DetectFeatures(grey, 1000, 2))) {
    most_unlimited = std::max(most_unlimited, n);
  }
  ASSERT_GT(most_unlimited, 3);
  // ... so the limit binds: no (detector, block) exceeds it, and every full
  // block of either detector reaches it. 97 x 71 px make 4 x 3 blocks.
  for (const int per_block : {1, 3}) {
    const std::vector<Feature> features = DetectFeatures(grey, per_block, 2);
    const auto count = CountPerBlock(features);
    for (const auto& [key, n] : count) {
      EXPECT_LE(n, per_block) << "per_block " << per_block << ", kind " << std::get<0>(key)
                              << ", block (" << std::get<1>(key) << ", " << std::get<2>(key) << ")";
    }
    for (const int kind : {0, 1}) {
      for (int by = 0; by < 2; ++by) {
        for (int bx = 0; bx < 3; ++bx) {
          const auto it = count.find({kind, bx, by});
          EXPECT_TRUE(it != count.end() && it->second == per_block)
              << "per_block " << per_block << ", kind " << kind << ", block (" << bx << ", " << by
              << ")";
        }
      }
    }
  }
}

TEST(DetectFeatures, KeepsTheStrongestOfEachBlock) {
  const cv::Mat grey = Checkerboard(6);
  const std::vector<Feature> all = DetectFeatures(grey, 1000, 2);
  const std::vector<Feature> kept = DetectFeatures(grey, 2, 2);
  // Within each (detector, block), no dropped feature is stronger than a kept one.
  std::map<std::tuple<int, int, int>, float> weakest_kept;
  for (const Feature& f : kept) {
    const std::tuple<int, int, int> key{static_cast<int>(f.kind),
                                        static_cast<int>(f.uv.x()) / kFeatureBlock,
                                        static_cast<int>(f.uv.y()) / kFeatureBlock};
    auto it = weakest_kept.find(key);
    if (it == weakest_kept.end()) {
      weakest_kept[key] = f.strength;
    } else {
      it->second = std::min(it->second, f.strength);
    }
  }
  for (const Feature& f : all) {
    const std::tuple<int, int, int> key{static_cast<int>(f.kind),
                                        static_cast<int>(f.uv.x()) / kFeatureBlock,
                                        static_cast<int>(f.uv.y()) / kFeatureBlock};
    const bool was_kept = std::any_of(kept.begin(), kept.end(), [&](const Feature& k) {
      return k.kind == f.kind && k.uv == f.uv;
    });
    if (was_kept) continue;
    ASSERT_TRUE(weakest_kept.count(key));
    EXPECT_LE(f.strength, weakest_kept[key]) << "dropped (" << f.uv.transpose() << ")";
  }
}

// Each (detector, block)'s features are ranked 0, 1, ... from the strongest:
// the first few of each block seed first (first_features_per_block).
TEST(DetectFeatures, RanksEachBlocksFeaturesFromTheStrongest) {
  const std::vector<Feature> kept = DetectFeatures(Checkerboard(6), 3, 2);
  std::map<std::tuple<int, int, int>, std::vector<const Feature*>> by_block;
  for (const Feature& f : kept) {
    by_block[{static_cast<int>(f.kind), static_cast<int>(f.uv.x()) / kFeatureBlock,
              static_cast<int>(f.uv.y()) / kFeatureBlock}]
        .push_back(&f);
  }
  ASSERT_GE(by_block.size(), 12u);  // both detectors over 4 x 3 blocks
  for (const auto& [key, block] : by_block) {
    std::vector<int> ranks;
    for (const Feature* f : block) ranks.push_back(f->block_rank);
    std::sort(ranks.begin(), ranks.end());
    for (size_t r = 0; r < ranks.size(); ++r) EXPECT_EQ(ranks[r], static_cast<int>(r));
    for (const Feature* a : block) {
      for (const Feature* b : block) {
        if (a->block_rank < b->block_rank) {
          EXPECT_GE(a->strength, b->strength)
              << "(" << a->uv.transpose() << ") ranked before (" << b->uv.transpose() << ")";
        }
      }
    }
  }
}

TEST(DetectFeatures, MarginIsRespected) {
  const cv::Mat grey = Checkerboard(6);
  constexpr int kMargin = 7;
  // Without a margin, the checkerboard's corners near the border are found ...
  const std::vector<Feature> unrestricted = DetectFeatures(grey, 1000, 0);
  const auto near_border = [&](const Feature& f, int margin) {
    return f.uv.x() < margin || f.uv.y() < margin || f.uv.x() > kWidth - 1 - margin ||
           f.uv.y() > kHeight - 1 - margin;
  };
  ASSERT_TRUE(std::any_of(unrestricted.begin(), unrestricted.end(),
                          [&](const Feature& f) { return near_border(f, kMargin); }));
  // ... and with one, none is closer to the border than the margin.
  const std::vector<Feature> features = DetectFeatures(grey, 1000, kMargin);
  ASSERT_FALSE(features.empty());
  for (const Feature& f : features) {
    EXPECT_FALSE(near_border(f, kMargin)) << "(" << f.uv.transpose() << ")";
  }
}

TEST(DetectFeatures, ConstantImageHasNoFeatures) {
  for (const float value : {0.0f, 50.0f, 128.0f, 200.0f, 255.0f}) {
    const cv::Mat grey(kHeight, kWidth, CV_32F, cv::Scalar(value));
    const std::vector<Feature> features = DetectFeatures(grey, 4, 0);
    EXPECT_TRUE(OfKind(features, FeatureKind::kHarris).empty()) << "grey " << value;
    const std::vector<Feature> dog = OfKind(features, FeatureKind::kDog);
    EXPECT_TRUE(dog.empty()) << "grey " << value << ": " << dog.size()
                             << " DoG features, the first of strength " << dog.front().strength;
  }
}

TEST(DetectEdges, FindsTheSquareOutlinesAndNothingElse) {
  const cv::Mat edges = DetectEdges(SquaresImage(), 40, 120);
  ASSERT_EQ(edges.type(), CV_8U);
  ASSERT_EQ(edges.cols, kWidth);
  ASSERT_EQ(edges.rows, kHeight);
  // Every edge pixel is on the ring of pixels just inside or just outside an
  // outline.
  int edge_pixels = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const uint8_t e = edges.at<uint8_t>(y, x);
      ASSERT_TRUE(e == 0 || e == 255) << int{e};
      if (e == 0) continue;
      ++edge_pixels;
      EXPECT_LE(DistanceToOutlines(Eigen::Vector2d(x, y)), 0.5)
          << "edge at (" << x << ", " << y << ")";
    }
  }
  // Each side of each square is traced along its length (the corners'
  // pixels aside, where Canny may cut across).
  for (const Square& s : Squares()) {
    const int x1 = s.x0 + s.size - 1, y1 = s.y0 + s.size - 1;
    auto on_edge = [&](int x, int y) { return edges.at<uint8_t>(y, x) != 0; };
    int traced = 0, positions = 0;
    for (int t = 1; t < s.size - 1; ++t) {
      positions += 4;
      traced += on_edge(s.x0 + t, s.y0) || on_edge(s.x0 + t, s.y0 - 1);  // top
      traced += on_edge(s.x0 + t, y1) || on_edge(s.x0 + t, y1 + 1);      // bottom
      traced += on_edge(s.x0, s.y0 + t) || on_edge(s.x0 - 1, s.y0 + t);  // left
      traced += on_edge(x1, s.y0 + t) || on_edge(x1 + 1, s.y0 + t);      // right
    }
    EXPECT_EQ(traced, positions) << "square at (" << s.x0 << ", " << s.y0 << ")";
  }
  EXPECT_GT(edge_pixels, 0);
}

TEST(DetectEdges, ConstantImageHasNoEdges) {
  const cv::Mat grey(kHeight, kWidth, CV_32F, cv::Scalar(128.0f));
  EXPECT_EQ(cv::countNonZero(DetectEdges(grey, 40, 120)), 0);
}

}  // namespace
}  // namespace sapmvs

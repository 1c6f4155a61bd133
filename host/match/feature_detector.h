#pragma once
// Seed features (method.md 3.4, 3.7): Harris corners and difference-of-Gaussian
// blobs, at most a few of each per 32 x 32 block so that seeds cover the whole
// image; and edge pixels (Canny) for the propagation barriers.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace sapmvs {

enum class FeatureKind { kHarris = 0, kDog = 1 };

struct Feature {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // pixel, (0,0) = centre of the top-left pixel
  FeatureKind kind = FeatureKind::kHarris;
  float strength = 0;  // detector response (|DoG| or Harris), for ranking within a block
  int block_rank = 0;  // 0 = the strongest of its detector in its block
};

// Side of the blocks features are spread over, pixels (PMVS's 32).
inline constexpr int kFeatureBlock = 32;

// Features of `grey` (CV_32F, 0..255): per detector, the `per_block`
// strongest 3x3 local maxima of each kFeatureBlock block whose response
// exceeds a small fraction of the image's strongest, at least `margin`
// pixels from the border.
std::vector<Feature> DetectFeatures(const cv::Mat& grey, int per_block, int margin);

// Canny edge mask (CV_8U, 255 = edge) of `grey` (CV_32F, 0..255).
cv::Mat DetectEdges(const cv::Mat& grey, double low, double high);

}  // namespace sapmvs

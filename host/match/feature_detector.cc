#include "match/feature_detector.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace sapmvs {
namespace {

// Response below this fraction of the image's maximum is noise: flat ground
// would otherwise fill every block with features that match nothing.
constexpr float kMinRelativeResponse = 0.01f;
// Absolute floors on 0..255 grey: a DoG of half a grey level, or a Harris
// response of a corner with gradients of about half a grey level per pixel,
// is quantisation or rounding noise, not texture (a constant image must give
// no features at all).
constexpr float kMinDogResponse = 0.5f;
constexpr float kMinHarrisResponse = 1.0f;

void KeepBlockMaxima(const cv::Mat& response, FeatureKind kind, int per_block, int margin,
                     float min_response, std::vector<Feature>* out) {
  double max_value = 0;
  cv::minMaxLoc(response, nullptr, &max_value);
  if (!(max_value > min_response)) return;
  const float floor_value =
      std::max(min_response, static_cast<float>(max_value) * kMinRelativeResponse);
  cv::Mat dilated;
  cv::dilate(response, dilated, cv::Mat());
  const int w = response.cols, h = response.rows;
  for (int by = 0; by < h; by += kFeatureBlock) {
    for (int bx = 0; bx < w; bx += kFeatureBlock) {
      std::vector<Feature> block;
      for (int y = std::max(by, margin); y < std::min(by + kFeatureBlock, h - margin); ++y) {
        const float* r = response.ptr<float>(y);
        const float* d = dilated.ptr<float>(y);
        for (int x = std::max(bx, margin); x < std::min(bx + kFeatureBlock, w - margin); ++x) {
          if (r[x] > floor_value && r[x] >= d[x]) {
            Feature f;
            f.uv = Eigen::Vector2d(x, y);
            f.kind = kind;
            f.strength = r[x];
            block.push_back(f);
          }
        }
      }
      const size_t keep = std::min(block.size(), static_cast<size_t>(per_block));
      std::partial_sort(block.begin(), block.begin() + keep, block.end(),
                        [](const Feature& a, const Feature& b) { return a.strength > b.strength; });
      for (size_t k = 0; k < keep; ++k) block[k].block_rank = static_cast<int>(k);
      out->insert(out->end(), block.begin(), block.begin() + keep);
    }
  }
}

}  // namespace

std::vector<Feature> DetectFeatures(const cv::Mat& grey, int per_block, int margin) {
  std::vector<Feature> features;
  cv::Mat harris;
  cv::cornerHarris(grey, harris, 3, 3, 0.04);
  KeepBlockMaxima(harris, FeatureKind::kHarris, per_block, margin, kMinHarrisResponse, &features);
  // DoG at PMVS's scale: sigma 1 against sigma 1.6; blobs of either sign.
  cv::Mat g1, g2;
  cv::GaussianBlur(grey, g1, cv::Size(0, 0), 1.0);
  cv::GaussianBlur(grey, g2, cv::Size(0, 0), 1.6);
  cv::Mat dog = cv::abs(g1 - g2);
  KeepBlockMaxima(dog, FeatureKind::kDog, per_block, margin, kMinDogResponse, &features);
  return features;
}

cv::Mat DetectEdges(const cv::Mat& grey, double low, double high) {
  cv::Mat grey8;
  grey.convertTo(grey8, CV_8U);
  cv::Mat edges;
  cv::Canny(grey8, edges, low, high, 3, true);
  return edges;
}

}  // namespace sapmvs

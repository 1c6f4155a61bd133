#include "sapmvs/block/block.h"

#include <algorithm>
#include <cmath>

namespace sapmvs {

int Block::FindImage(const std::string& name) const {
  for (size_t i = 0; i < images.size(); ++i) {
    if (images[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

Eigen::Vector3d ChooseLocalOrigin(const std::vector<BlockImage>& images) {
  if (images.empty()) return Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = images.front().camera.center(), hi = lo, sum = Eigen::Vector3d::Zero();
  for (const BlockImage& im : images) {
    lo = lo.cwiseMin(im.camera.center());
    hi = hi.cwiseMax(im.camera.center());
    sum += im.camera.center();
  }
  const Eigen::Vector3d mean = sum / static_cast<double>(images.size());
  const double extent = std::max((hi - lo).maxCoeff(), 1e-9 * std::max(1.0, mean.norm()));
  const double quantum = std::pow(10.0, std::floor(std::log10(extent)) - 3);
  return (mean / quantum).array().round() * quantum;
}

}  // namespace sapmvs

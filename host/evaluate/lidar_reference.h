#pragma once
// Reference heights from airborne LiDAR: the mean Z of the LiDAR points
// within a horizontal (XY) distance of a query, found with a FLANN KD-tree
// over the LiDAR's XY.

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace sapmvs {

class LidarReference {
 public:
  // Builds the 2-D tree over the XY of `points` (at least one, all finite).
  explicit LidarReference(const std::vector<Eigen::Vector3d>& points);
  ~LidarReference();
  LidarReference(const LidarReference&) = delete;
  LidarReference& operator=(const LidarReference&) = delete;

  size_t size() const { return z_.size(); }

  // The LiDAR's point spacing: the median XY distance from a point to its
  // nearest neighbour at a non-zero distance (several returns of one pulse
  // share an XY), over at most kSpacingSamples points taken at an even
  // stride. NaN when no point has a distinct neighbour.
  double MedianSpacing() const;
  static constexpr size_t kSpacingSamples = 200000;

  // For each query, the mean Z of the LiDAR points at XY distance <= radius;
  // NaN where there is none. `progress` draws a bar on a terminal.
  std::vector<double> MeanHeights(const std::vector<Eigen::Vector3d>& queries, double radius,
                                  bool progress = false) const;

 private:
  struct Index;

  // FLANN works on float, where X ~ 5e5 or Y ~ 5.4e6 would be rounded to
  // 0.03 or 0.5 units. The tree is therefore built on XY relative to
  // `origin_` (the data's centre, rounded), and every candidate FLANN returns
  // is accepted or rejected on the exact distance computed in double.
  Eigen::Vector2d origin_;
  std::vector<Eigen::Vector2d> xy_;  // relative to origin_, double
  std::vector<double> z_;
  std::vector<float> xy_float_;    // FLANN's copy of xy_
  double max_abs_coordinate_ = 0;  // largest |relative coordinate|, for the float margin
  std::unique_ptr<Index> index_;
};

}  // namespace sapmvs

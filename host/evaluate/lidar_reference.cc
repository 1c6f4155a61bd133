#include "evaluate/lidar_reference.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "sapmvs/util/progress.h"

namespace sapmvs {
namespace {

// Queries per FLANN call: bounds the memory of the per-query result vectors.
constexpr size_t kChunkQueries = 1 << 16;
// Candidates (index + distance, 12 bytes each) one FLANN call may return,
// about 200 MB: a large radius finds many points per query, and the chunk
// shrinks so that the result vectors stay within this.
constexpr double kChunkCandidates = 16e6;
// Neighbours asked for when measuring the spacing: enough to step over the
// returns of one pulse that share its XY.
constexpr int kSpacingNeighbours = 8;
// A float holds 24 bits; a relative coordinate c is off by at most |c| 2^-24
// and the squared distance FLANN forms adds a few roundings more. Searching
// with the radius widened by this share of the coordinates' size (~8 float
// epsilons) never misses a point that is within the radius in double.
constexpr double kFloatMargin = 1e-6;

}  // namespace

struct LidarReference::Index {
  explicit Index(const flann::Matrix<float>& data)
      : index(data, flann::KDTreeSingleIndexParams(/*leaf_max_size=*/10)) {
    index.buildIndex();
  }
  flann::Index<flann::L2<float>> index;
};

LidarReference::LidarReference(const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) throw Error("LiDAR reference: no points (expected at least one)");
  Eigen::Vector2d lo = points[0].head<2>(), hi = lo;
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite()) throw Error("LiDAR reference: a point has a non-finite coordinate");
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  origin_ = (0.5 * (lo + hi)).array().round();
  xy_.reserve(points.size());
  z_.reserve(points.size());
  xy_float_.reserve(2 * points.size());
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector2d r = p.head<2>() - origin_;
    xy_.push_back(r);
    z_.push_back(p.z());
    xy_float_.push_back(static_cast<float>(r.x()));
    xy_float_.push_back(static_cast<float>(r.y()));
    max_abs_coordinate_ = std::max(max_abs_coordinate_, r.cwiseAbs().maxCoeff());
  }
  index_ = std::make_unique<Index>(flann::Matrix<float>(xy_float_.data(), xy_.size(), 2));
}

LidarReference::~LidarReference() = default;

double LidarReference::MedianSpacing() const {
  if (xy_.size() < 2) return kNaN;
  const size_t stride = (xy_.size() + kSpacingSamples - 1) / kSpacingSamples;
  std::vector<float> queries;
  std::vector<size_t> sample;
  for (size_t i = 0; i < xy_.size(); i += stride) {
    sample.push_back(i);
    queries.push_back(xy_float_[2 * i]);
    queries.push_back(xy_float_[2 * i + 1]);
  }
  const int k = static_cast<int>(std::min<size_t>(kSpacingNeighbours, xy_.size()));
  std::vector<size_t> indices(sample.size() * k);
  std::vector<float> dists(sample.size() * k);
  flann::Matrix<size_t> indices_m(indices.data(), sample.size(), k);
  flann::Matrix<float> dists_m(dists.data(), sample.size(), k);
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED);
  params.cores = 0;
  index_->index.knnSearch(flann::Matrix<float>(queries.data(), sample.size(), 2), indices_m,
                          dists_m, k, params);
  std::vector<double> nearest;
  nearest.reserve(sample.size());
  for (size_t s = 0; s < sample.size(); ++s) {
    double best = std::numeric_limits<double>::infinity();
    for (int j = 0; j < k; ++j) {
      const size_t n = indices_m[s][j];
      if (n >= xy_.size()) continue;  // FLANN pads missing neighbours
      const double d = (xy_[n] - xy_[sample[s]]).norm();
      if (d > 0) best = std::min(best, d);
    }
    if (std::isfinite(best)) nearest.push_back(best);
  }
  if (nearest.empty()) return kNaN;
  const auto mid = nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2);
  std::nth_element(nearest.begin(), mid, nearest.end());
  if (nearest.size() % 2 == 1) return *mid;
  // Even count: the mean of the two middle values, so that a regular grid
  // gives its spacing whatever the sample.
  return 0.5 * (*mid + *std::max_element(nearest.begin(), mid));
}

std::vector<double> LidarReference::MeanHeights(const std::vector<Eigen::Vector3d>& queries,
                                                double radius, bool progress) const {
  if (!(radius > 0) || !std::isfinite(radius)) {
    throw Error("LiDAR reference: search radius " + std::to_string(radius) +
                " (expected a positive, finite distance)");
  }
  std::vector<double> heights(queries.size(), kNaN);
  const double radius2 = radius * radius;
  Progress bar("reference heights", static_cast<long>(queries.size()), progress);
  std::vector<float> q;
  std::vector<std::vector<size_t>> indices;
  std::vector<std::vector<float>> dists;
  // The first chunk is small; later ones are sized from the candidates per
  // query the previous one found.
  size_t chunk = 1024;
  for (size_t first = 0, n = 0; first < queries.size(); first += n) {
    n = std::min(chunk, queries.size() - first);
    q.resize(2 * n);
    double max_abs = max_abs_coordinate_;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d r = queries[first + i].head<2>() - origin_;
      q[2 * i] = static_cast<float>(r.x());
      q[2 * i + 1] = static_cast<float>(r.y());
      max_abs = std::max(max_abs, r.cwiseAbs().maxCoeff());
    }
    const double widened = radius + kFloatMargin * (max_abs + radius);
    flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED, 0, /*sorted=*/false);
    params.cores = 0;
    index_->index.radiusSearch(flann::Matrix<float>(q.data(), n, 2), indices, dists,
                               static_cast<float>(widened * widened), params);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < static_cast<long>(n); ++i) {
      const Eigen::Vector2d r = queries[first + i].head<2>() - origin_;
      double sum = 0;
      long count = 0;
      for (size_t j : indices[i]) {
        if ((xy_[j] - r).squaredNorm() <= radius2) {
          sum += z_[j];
          ++count;
        }
      }
      if (count > 0) heights[first + i] = sum / static_cast<double>(count);
    }
    size_t found = 0;
    for (size_t i = 0; i < n; ++i) found += indices[i].size();
    const double per_query = std::max(1.0, static_cast<double>(found) / static_cast<double>(n));
    chunk = static_cast<size_t>(
        std::clamp(kChunkCandidates / per_query, 1.0, static_cast<double>(kChunkQueries)));
    bar.Advance(static_cast<long>(n));
  }
  bar.Finish();
  return heights;
}

}  // namespace sapmvs

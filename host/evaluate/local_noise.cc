#include "sapmvs/evaluate/local_noise.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "sapmvs/util/error.h"

namespace sapmvs {

std::string LocalNoiseOptions::Problem() const {
  std::ostringstream s;
  if (samples < 1) {
    s << "samples >= 1 (samples = " << samples << ")";
  } else if (!(std::isfinite(radius) && radius > 0)) {
    s << "a radius > 0 (radius = " << radius << ")";
  } else if (min_neighbours < 3 || neighbours < min_neighbours) {
    s << "3 <= min_neighbours <= neighbours (" << min_neighbours << ", " << neighbours << ")";
  }
  return s.str();
}

namespace {

struct Key {
  int64_t x, y;
  bool operator==(const Key& o) const { return x == o.x && y == o.y; }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    return static_cast<size_t>(static_cast<uint64_t>(k.x) * 73856093ULL ^
                               static_cast<uint64_t>(k.y) * 19349663ULL);
  }
};

Key CellOf(const Eigen::Vector3d& p, double side) {
  return {static_cast<int64_t>(std::floor(p.x() / side)),
          static_cast<int64_t>(std::floor(p.y() / side))};
}

}  // namespace

LocalNoise MeasureLocalNoise(const PointCloud& cloud, const LocalNoiseOptions& options) {
  if (const std::string p = options.Problem(); !p.empty())
    throw Error("local noise: expected " + p);
  LocalNoise result;
  const size_t n = cloud.points.size();
  if (n == 0) return result;
  // Columns of side `radius`: the neighbours lie in the 3 x 3 around a point.
  std::unordered_map<Key, std::vector<uint32_t>, KeyHash> columns;
  for (size_t i = 0; i < n; ++i) {
    columns[CellOf(cloud.points[i].position, options.radius)].push_back(static_cast<uint32_t>(i));
  }
  std::mt19937 rng(options.seed);
  std::vector<size_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = i;
  if (static_cast<long>(n) > options.samples) {
    // The first `samples` of a partial Fisher-Yates shuffle.
    for (long k = 0; k < options.samples; ++k) {
      std::uniform_int_distribution<size_t> pick(static_cast<size_t>(k), n - 1);
      std::swap(order[static_cast<size_t>(k)], order[pick(rng)]);
    }
    order.resize(static_cast<size_t>(options.samples));
  }
  const double r2 = options.radius * options.radius;
  std::vector<double> distances;
  std::vector<uint32_t> near;
  for (const size_t i : order) {
    const Eigen::Vector3d& p = cloud.points[i].position;
    const Key c = CellOf(p, options.radius);
    near.clear();
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = columns.find({c.x + dx, c.y + dy});
        if (it == columns.end()) continue;
        for (const uint32_t j : it->second) {
          if (j != i && (cloud.points[j].position - p).head<2>().squaredNorm() <= r2) {
            near.push_back(j);
          }
        }
      }
    }
    if (static_cast<int>(near.size()) < options.min_neighbours) continue;
    const size_t k = std::min(near.size(), static_cast<size_t>(options.neighbours));
    for (size_t a = 0; a < k; ++a) {
      std::uniform_int_distribution<size_t> pick(a, near.size() - 1);
      std::swap(near[a], near[pick(rng)]);
    }
    // Relative to p, so that UTM-sized coordinates keep their digits.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (size_t a = 0; a < k; ++a) mean += cloud.points[near[a]].position - p;
    mean /= static_cast<double>(k);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (size_t a = 0; a < k; ++a) {
      const Eigen::Vector3d d = cloud.points[near[a]].position - p - mean;
      cov += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d normal = eig.eigenvectors().col(0);  // smallest eigenvalue
    distances.push_back(std::abs(normal.dot(-mean)));
  }
  result.sampled = static_cast<long>(distances.size());
  if (distances.empty()) return result;
  auto quantile = [&](double q) {
    const size_t at = std::min(distances.size() - 1, static_cast<size_t>(q * distances.size()));
    std::nth_element(distances.begin(), distances.begin() + static_cast<long>(at), distances.end());
    return distances[at];
  };
  result.median = quantile(0.5);
  result.p90 = quantile(0.9);
  return result;
}

std::set<std::pair<int64_t, int64_t>> CoveredCells(const PointCloud& cloud, double cell) {
  if (!(std::isfinite(cell) && cell > 0)) throw Error("ground cover: expected a cell side > 0");
  std::set<std::pair<int64_t, int64_t>> cells;
  for (const CloudPoint& p : cloud.points) {
    const Key k = CellOf(p.position, cell);
    cells.emplace(k.x, k.y);
  }
  return cells;
}

}  // namespace sapmvs

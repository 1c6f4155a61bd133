#include "sapmvs/run/core_index.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "sapmvs/run/cloud_merge.h"

namespace sapmvs {
namespace {

// About this many grid cells per centre: a cell then spans half the
// centres' spacing, and lists the dozen centres around it.
constexpr double kCellsPerCenter = 4;
constexpr double kMaxCells = 1 << 22;

double DistanceToBox(const Eigen::Vector2d& p, const Eigen::Vector2d& lo,
                     const Eigen::Vector2d& hi) {
  return (p.cwiseMax(lo).cwiseMin(hi) - p).norm();
}

// The nearest of `ids` (ascending) to p, ties to the lower index; -1 for
// none.
template <typename Ids>
int NearestOf(const std::vector<Eigen::Vector2d>& centers, const Ids& ids,
              const Eigen::Vector2d& p) {
  int best = -1;
  double best_d2 = 0;
  for (const int g : ids) {
    const double d2 = (p - centers[g]).squaredNorm();
    if (best < 0 || d2 < best_d2) {
      best = g;
      best_d2 = d2;
    }
  }
  return best;
}

// NearestOf, and p's distance to the border of its core with each other
// centre of `ids`, the least.
template <typename Ids>
std::pair<int, double> NearestOfAndBorder(const std::vector<Eigen::Vector2d>& centers,
                                          const Ids& ids, const Eigen::Vector2d& p) {
  const int own = NearestOf(centers, ids, p);
  double border = std::numeric_limits<double>::infinity();
  if (own < 0) return {own, border};
  for (const int g : ids)
    if (g != own) border = std::min(border, BeyondBisector(centers[own], centers[g], p));
  return {own, border};
}

// 0 .. n - 1, for a loop over every centre without a list of them.
struct AllOf {
  int n;
  struct Iterator {
    int i;
    int operator*() const { return i; }
    Iterator& operator++() {
      ++i;
      return *this;
    }
    bool operator!=(const Iterator& o) const { return i != o.i; }
  };
  Iterator begin() const { return {0}; }
  Iterator end() const { return {n}; }
};

}  // namespace

int CoreOwner(const std::vector<Eigen::Vector2d>& centers, double x, double y) {
  return NearestOf(centers, AllOf{static_cast<int>(centers.size())}, {x, y});
}

std::pair<int, double> CoreOwnerAndBorder(const std::vector<Eigen::Vector2d>& centers, double x,
                                          double y) {
  return NearestOfAndBorder(centers, AllOf{static_cast<int>(centers.size())}, {x, y});
}

CoreIndex::CoreIndex(std::vector<Eigen::Vector2d> centers, double reach, const Eigen::Vector2d& lo,
                     const Eigen::Vector2d& hi)
    : centers_(std::move(centers)) {
  Build(reach, lo, hi);
}

CoreIndex::CoreIndex(std::vector<Eigen::Vector2d> centers, double reach)
    : centers_(std::move(centers)) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  double spacing = 0;
  for (size_t a = 0; a < centers_.size(); ++a) {
    lo = lo.cwiseMin(centers_[a]);
    hi = hi.cwiseMax(centers_[a]);
    double nearest = std::numeric_limits<double>::infinity();
    for (size_t b = 0; b < centers_.size(); ++b)
      if (b != a) nearest = std::min(nearest, (centers_[b] - centers_[a]).norm());
    if (std::isfinite(nearest)) spacing = std::max(spacing, nearest);
  }
  const double grow = 2 * spacing + 2 * reach;
  Build(reach, lo.array() - grow, hi.array() + grow);
}

void CoreIndex::Build(double reach, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
  all_.resize(centers_.size());
  std::iota(all_.begin(), all_.end(), 0);
  const Eigen::Vector2d size = hi - lo;
  if (centers_.size() < 3 || !lo.allFinite() || !hi.allFinite() || !(size.minCoeff() > 0) ||
      !(reach >= 0))
    return;  // every point looks at every centre
  const double cells = std::min(kMaxCells, kCellsPerCenter * static_cast<double>(centers_.size()));
  side_ = std::sqrt(size.x() * size.y() / cells);
  nx_ = std::max(1, static_cast<int>(std::ceil(size.x() / side_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(size.y() / side_)));
  lo_ = lo;
  cells_.assign(static_cast<size_t>(nx_) * ny_, {});
  const double half_diagonal = side_ * std::sqrt(0.5);
  for (int y = 0; y < ny_; ++y) {
    for (int x = 0; x < nx_; ++x) {
      const Eigen::Vector2d box_lo = lo_ + side_ * Eigen::Vector2d(x, y);
      const Eigen::Vector2d box_hi = box_lo + Eigen::Vector2d::Constant(side_);
      const Eigen::Vector2d mid = box_lo + Eigen::Vector2d::Constant(0.5 * side_);
      double nearest = std::numeric_limits<double>::infinity();
      for (const Eigen::Vector2d& c : centers_) nearest = std::min(nearest, (c - mid).norm());
      // Any point of the box lies within nearest + half_diagonal of its
      // own centre; padded against rounding, as the test is strict.
      const double limit = (nearest + half_diagonal + 2 * reach) * (1 + 1e-9) + 1e-9;
      std::vector<int>& list = cells_[static_cast<size_t>(y) * nx_ + x];
      for (int g = 0; g < static_cast<int>(centers_.size()); ++g)
        if (DistanceToBox(centers_[g], box_lo, box_hi) <= limit) list.push_back(g);
    }
  }
}

const std::vector<int>& CoreIndex::Candidates(const Eigen::Vector2d& p) const {
  if (cells_.empty()) return all_;
  const double fx = std::floor((p.x() - lo_.x()) / side_);
  const double fy = std::floor((p.y() - lo_.y()) / side_);
  if (!(fx >= 0 && fx < nx_ && fy >= 0 && fy < ny_)) return all_;
  return cells_[static_cast<size_t>(fy) * nx_ + static_cast<size_t>(fx)];
}

int CoreIndex::Owner(const Eigen::Vector2d& p) const {
  return NearestOf(centers_, Candidates(p), p);
}

std::pair<int, double> CoreIndex::OwnerAndBorder(const Eigen::Vector2d& p) const {
  return NearestOfAndBorder(centers_, Candidates(p), p);
}

std::pair<int, int> CoreIndex::TwoNearest(const Eigen::Vector2d& p) const {
  int first = -1, second = -1;
  double d1 = 0, d2 = 0;
  for (const int g : Candidates(p)) {
    const double d = (p - centers_[g]).squaredNorm();
    if (first < 0 || d < d1) {
      second = first, d2 = d1;
      first = g, d1 = d;
    } else if (second < 0 || d < d2) {
      second = g, d2 = d;
    }
  }
  return {first, second};
}

}  // namespace sapmvs

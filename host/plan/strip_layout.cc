// The layout-only strip detection (StripsFromLayout), for blocks without a
// flight order:
//  1. Headings: the camera's image x axis on the ground (kappa, for a frame
//     camera flown with image x along track). Headings are clustered on the
//     circle; a turn between strips (alternating directions, a cross strip at
//     90 deg) separates them.
//  2. Within one heading, the along-track axis is the mean direction from each
//     centre to its nearest neighbour (the forward base is shorter than the
//     strip spacing in any block flown for stereo), and the base is the
//     median nearest-neighbour distance.
//  3. Centres are split where their cross-track offsets jump (parallel strips
//     flown the same way) and where the along-track spacing jumps (a strip
//     broken off and resumed with no overlap).
//  4. Each strip is ordered in flight order: the block's own order when it
//     runs along the strip, else the direction of the image x axis.
#include "plan/strip_detection.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace sapmvs {
namespace {

// Headings within this of each other (chained) belong to one direction of
// flight. Crab angles into a side wind reach about 15 deg on small UAVs and
// the simulator adds 2 deg of kappa noise; a turn between strips is 90 or
// 180 deg.
constexpr double kHeadingToleranceDeg = 30.0;
// Parallel strips flown the same way are split where the sorted cross-track
// offsets jump by more than this many bases. GNSS noise and wind drift move
// centres by a small share of the base; strips lie at least one base apart
// (the side step of any stereo block exceeds its forward base).
constexpr double kCrossTrackGap = 0.5;
// Share of consecutive pairs (along the strip) whose block indices must
// increase, or decrease, for the block's order to count as the flight order.
constexpr double kOrderAgreement = 0.8;

// Heading of the image x axis on the ground, degrees in [0, 360).
double HeadingDeg(const Camera& cam) {
  Eigen::Vector2d x = cam.rotation().row(0).head<2>().transpose();
  if (x.norm() < 1e-6) {
    // Image x points straight down: fall back on the image "up" axis
    // (OpenCV -y), turned so that level cameras agree with the x heading.
    const Eigen::Vector2d up = -cam.rotation().row(1).head<2>().transpose();
    x = Eigen::Vector2d(up.y(), -up.x());
  }
  double deg = std::atan2(x.y(), x.x()) * 180.0 / M_PI;
  if (deg < 0) deg += 360.0;
  return deg;
}

// Splits `ids` (sorted by `key`) wherever consecutive keys differ by more
// than `gap`.
std::vector<std::vector<int>> SplitAtGaps(std::vector<int> ids, const std::vector<double>& key,
                                          double gap) {
  std::sort(ids.begin(), ids.end(), [&](int a, int b) { return key[a] < key[b]; });
  std::vector<std::vector<int>> out;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (i == 0 || key[ids[i]] - key[ids[i - 1]] > gap) out.emplace_back();
    out.back().push_back(ids[i]);
  }
  return out;
}

// Clusters of images whose headings chain within kHeadingToleranceDeg.
std::vector<std::vector<int>> HeadingClusters(const std::vector<double>& heading) {
  std::vector<int> order(heading.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return heading[a] < heading[b]; });
  const size_t n = order.size();
  // Start after the widest gap on the circle, so a cluster around 0/360 deg
  // is not cut in two.
  size_t start = 0;
  double widest = -1;
  for (size_t i = 0; i < n; ++i) {
    const double prev = heading[order[(i + n - 1) % n]];
    double gap = heading[order[i]] - prev;
    if (gap < 0 || n == 1) gap += 360.0;
    if (gap > widest) {
      widest = gap;
      start = i;
    }
  }
  std::vector<std::vector<int>> out;
  for (size_t k = 0; k < n; ++k) {
    const size_t i = (start + k) % n;
    double gap = heading[order[i]] - heading[order[(i + n - 1) % n]];
    if (gap < 0) gap += 360.0;
    if (k == 0 || gap > kHeadingToleranceDeg) out.emplace_back();
    out.back().push_back(order[i]);
  }
  return out;
}

struct Axis {
  Eigen::Vector2d along = Eigen::Vector2d::UnitX();
  double base = 0;  // median nearest-neighbour distance
};

Axis AlongTrackAxis(const std::vector<int>& ids, const std::vector<Eigen::Vector2d>& xy) {
  Axis axis;
  if (ids.size() < 2) return axis;
  // Orientation tensor of the unit nearest-neighbour directions: sign-free,
  // so links forwards and backwards along a strip agree.
  Eigen::Matrix2d tensor = Eigen::Matrix2d::Zero();
  std::vector<double> nearest;
  for (const int i : ids) {
    double best = INFINITY;
    Eigen::Vector2d link = Eigen::Vector2d::Zero();
    for (const int j : ids) {
      if (j == i) continue;
      const Eigen::Vector2d d = xy[j] - xy[i];
      if (d.norm() < best) {
        best = d.norm();
        link = d;
      }
    }
    nearest.push_back(best);
    if (best > 0) tensor += link * link.transpose() / (best * best);
  }
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  axis.base = nearest[nearest.size() / 2];
  if (tensor.trace() > 0) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(tensor);
    axis.along = eig.eigenvectors().col(1);  // largest eigenvalue last
  }
  return axis;
}

// Orders `strip` (sorted by along-track position) in flight order.
void OrderAlongFlight(const Block& block, const Eigen::Vector2d& along, std::vector<int>* strip) {
  const size_t n = strip->size();
  if (n < 2) return;
  if (n >= 3) {
    size_t increasing = 0;
    for (size_t i = 1; i < n; ++i) increasing += (*strip)[i] > (*strip)[i - 1];
    const double share = static_cast<double>(increasing) / static_cast<double>(n - 1);
    if (share >= kOrderAgreement) return;
    if (share <= 1 - kOrderAgreement) {
      std::reverse(strip->begin(), strip->end());
      return;
    }
  }
  // The block's order says nothing (shuffled, or two images): image x along
  // track is the photogrammetric convention (rotation.h), so its mean
  // direction is the direction of flight.
  Eigen::Vector2d x = Eigen::Vector2d::Zero();
  for (const int i : *strip) x += block.images[i].camera.rotation().row(0).head<2>().transpose();
  if (x.dot(along) < 0) std::reverse(strip->begin(), strip->end());
}

}  // namespace

std::vector<std::vector<int>> StripsFromLayout(const Block& block, const std::vector<int>& images) {
  const size_t n = block.images.size();
  std::vector<Eigen::Vector2d> xy(n);
  std::vector<double> heading(images.size());
  for (size_t k = 0; k < images.size(); ++k) {
    const Camera& cam = block.images[images[k]].camera;
    xy[images[k]] = (cam.center() - block.origin).head<2>();
    heading[k] = HeadingDeg(cam);
  }
  std::vector<std::vector<int>> strips;
  if (images.empty()) return strips;
  for (std::vector<int> cluster : HeadingClusters(heading)) {
    for (int& i : cluster) i = images[i];
    const Axis axis = AlongTrackAxis(cluster, xy);
    const Eigen::Vector2d across(-axis.along.y(), axis.along.x());
    std::vector<double> along_key(n, 0), across_key(n, 0);
    for (const int i : cluster) {
      along_key[i] = axis.along.dot(xy[i]);
      across_key[i] = across.dot(xy[i]);
    }
    // Coincident centres (base 0) stay together rather than splitting at
    // every rounding difference.
    const double base = std::max(axis.base, 1e-9);
    for (const std::vector<int>& line : SplitAtGaps(cluster, across_key, kCrossTrackGap * base)) {
      for (std::vector<int> strip : SplitAtGaps(line, along_key, kStripGapBases * base)) {
        OrderAlongFlight(block, axis.along, &strip);
        strips.push_back(std::move(strip));
      }
    }
  }
  std::sort(strips.begin(), strips.end(), [](const auto& a, const auto& b) {
    return *std::min_element(a.begin(), a.end()) < *std::min_element(b.begin(), b.end());
  });
  return strips;
}

}  // namespace sapmvs

#include "plan/strip_detection.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "plan/grouping_internal.h"
#include "sapmvs/block/block_geometry.h"

namespace sapmvs {
namespace {

// In flight order nearly every step goes to a neighbouring exposure; in a
// shuffled order most steps cross the block. Side steps and turns are a few
// steps of every strip, so the median step stays near the base.
constexpr double kOrderStep = 2.0;
// An image flown higher or lower than the median by more than this factor
// sees the ground at another scale (its GSD a quarter off the strips'): the
// climb and the descent pass through every height, while a strip, even
// hand-flown, holds its height within a few percent.
constexpr double kHeightRatio = 1.25;
// A step this far off the run's mean direction ends the run: hand-flown
// steps wander by 15-20 deg, a turn is 90 deg (side step) or 180 (reversal).
constexpr double kTurnDeg = 45.0;
// A step shorter than this share of the base (hovering, a climb above one
// spot) has no direction worth following.
constexpr double kHoverBases = 0.25;
// Fewest images of a strip: two images leave a patch no third view
// (min_image_num 3), so shorter runs are turns or strays.
constexpr size_t kMinStripImages = 3;
// An end image whose step leaves the strip's line by more than this is a
// turn photo, taken as the pilot began to turn: wander within a strip stays
// under it, a turn of 90 deg starts with a step well past it.
constexpr double kEndDeg = 30.0;

// Name order with digit runs compared as numbers (IMG_99 < IMG_100).
bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  auto digit = [](char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      size_t ie = i, je = j;
      while (ie < a.size() && digit(a[ie])) ++ie;
      while (je < b.size() && digit(b[je])) ++je;
      while (i + 1 < ie && a[i] == '0') ++i;
      while (j + 1 < je && b[j] == '0') ++j;
      if (ie - i != je - j) return ie - i < je - j;
      if (const int c = a.compare(i, ie - i, b, j, je - j); c != 0) return c < 0;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double AngleDeg(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const double c = a.normalized().dot(b.normalized());
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
}

// A run of the flight path: seq[first..last], and its mean step direction.
struct Run {
  size_t first = 0, last = 0;
  Eigen::Vector2d direction = Eigen::Vector2d::Zero();
  size_t Size() const { return last - first + 1; }
};

// Mean unit step of seq[first..last], hovering steps left out.
Eigen::Vector2d MeanStep(const std::vector<Eigen::Vector2d>& xy, const std::vector<int>& seq,
                         size_t first, size_t last, double hover) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (size_t k = first; k < last; ++k) {
    const Eigen::Vector2d d = xy[seq[k + 1]] - xy[seq[k]];
    if (d.norm() >= hover) sum += d.normalized();
  }
  return sum.norm() > 0 ? Eigen::Vector2d(sum.normalized()) : sum;
}

// Cuts `seq` into runs of steps that keep their mean direction.
std::vector<Run> CutRuns(const std::vector<Eigen::Vector2d>& xy, const std::vector<int>& seq,
                         double base) {
  std::vector<Run> runs;
  if (seq.empty()) return runs;
  Run run;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (size_t k = 0; k + 1 < seq.size(); ++k) {
    const Eigen::Vector2d d = xy[seq[k + 1]] - xy[seq[k]];
    const double len = d.norm();
    const bool hover = len < kHoverBases * base;
    const bool jump = len > kStripGapBases * base;
    if (jump || (!hover && sum.norm() > 0 && AngleDeg(d, sum) > kTurnDeg)) {
      run.last = k;
      runs.push_back(run);
      // A turn's step starts the next run at the turning image; a jump
      // starts it after the gap.
      run = Run{};
      run.first = jump ? k + 1 : k;
      sum.setZero();
    }
    if (!hover && !jump) sum += d / len;
  }
  run.last = seq.size() - 1;
  runs.push_back(run);
  return runs;
}

// Drops end images whose step leaves the run's line (turn photos).
void TrimEnds(const std::vector<Eigen::Vector2d>& xy, const std::vector<int>& seq, double hover,
              Run* run) {
  while (run->Size() > kMinStripImages) {
    // The line without its ends, which are what is being judged.
    const Eigen::Vector2d u = MeanStep(xy, seq, run->first + 1, run->last - 1, hover);
    if (u.norm() == 0) return;
    const Eigen::Vector2d head = xy[seq[run->first + 1]] - xy[seq[run->first]];
    const Eigen::Vector2d tail = xy[seq[run->last]] - xy[seq[run->last - 1]];
    if (tail.norm() >= hover && AngleDeg(tail, u) > kEndDeg) {
      --run->last;
    } else if (head.norm() >= hover && AngleDeg(head, u) > kEndDeg) {
      ++run->first;
    } else {
      return;
    }
  }
}

// Runs long enough to be strips and along the block's main direction, or
// across it (a cross strip) and as long as half the others.
std::vector<Run> StripRuns(std::vector<Run> runs) {
  std::vector<Run> kept;
  Eigen::Matrix2d tensor = Eigen::Matrix2d::Zero();
  for (const Run& r : runs) {
    if (r.Size() < kMinStripImages || r.direction.norm() == 0) continue;
    tensor += static_cast<double>(r.Size()) * r.direction * r.direction.transpose();
    kept.push_back(r);
  }
  if (kept.empty()) return kept;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(tensor);
  const Eigen::Vector2d axis = eig.eigenvectors().col(1);
  const double cos_turn = std::cos(kTurnDeg * M_PI / 180.0);
  std::vector<double> along;
  for (const Run& r : kept)
    if (std::abs(r.direction.dot(axis)) >= cos_turn) along.push_back(static_cast<double>(r.Size()));
  const double typical = Median(along);
  std::vector<Run> out;
  for (const Run& r : kept)
    if (std::abs(r.direction.dot(axis)) >= cos_turn || r.Size() >= typical / 2) out.push_back(r);
  return out;
}

// Why each image of no strip is one, in flight order.
std::vector<StripOutlier> Outliers(const std::vector<int>& order, const std::vector<int>& strip_of,
                                   const std::vector<double>& height, double median_height) {
  std::vector<StripOutlier> out;
  std::vector<int> before(order.size(), -1), after(order.size(), -1);
  for (size_t p = 0; p < order.size(); ++p)
    before[p] = strip_of[order[p]] >= 0 ? strip_of[order[p]] : (p ? before[p - 1] : -1);
  for (size_t p = order.size(); p-- > 0;)
    after[p] =
        strip_of[order[p]] >= 0 ? strip_of[order[p]] : (p + 1 < order.size() ? after[p + 1] : -1);
  for (size_t p = 0; p < order.size(); ++p) {
    const int i = order[p];
    if (strip_of[i] >= 0) continue;
    StripOutlier o;
    o.image = i;
    const std::string strip_a = std::to_string(before[p] + 1);
    const std::string strip_b = std::to_string(after[p] + 1);
    const std::string where = before[p] < 0  ? "before strip " + strip_b
                              : after[p] < 0 ? "after strip " + strip_a
                              : before[p] == after[p]
                                  ? "within strip " + strip_a
                                  : "between strips " + strip_a + " and " + strip_b;
    const double ratio = height[i] / median_height;
    if (std::isfinite(ratio) && (ratio > kHeightRatio || ratio < 1 / kHeightRatio)) {
      o.kind = OutlierKind::kClimb;
      o.reason = std::string(before[p] < 0  ? "climb"
                             : after[p] < 0 ? "descent"
                                            : "height") +
                 ": " + Fixed(height[i], 1) + " above the ground, " + Fixed(ratio, 2) +
                 " of the block's median " + Fixed(median_height, 1) + ", so another GSD (" +
                 where + ")";
    } else if (before[p] >= 0 && after[p] >= 0) {
      o.kind = OutlierKind::kTurn;
      o.reason = "turn " + where + ": its steps leave the strips' lines";
    } else {
      o.kind = OutlierKind::kStray;
      o.reason = "stray " + where + ": its steps leave the strip's line";
    }
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace

std::string ToString(OutlierKind kind) {
  switch (kind) {
    case OutlierKind::kClimb:
      return "climb";
    case OutlierKind::kTurn:
      return "turn";
    case OutlierKind::kStray:
      break;
  }
  return "stray";
}

std::vector<int> FlightOrder(const Block& block) {
  const size_t n = block.images.size();
  std::vector<int> by_block(n);
  std::iota(by_block.begin(), by_block.end(), 0);
  if (n < 3) return by_block;
  std::vector<int> by_name = by_block;
  std::stable_sort(by_name.begin(), by_name.end(), [&](int a, int b) {
    return NaturalLess(block.images[a].name, block.images[b].name);
  });
  auto centre = [&](int i) { return block.images[i].camera.center(); };
  auto steps = [&](const std::vector<int>& order) {
    std::vector<double> s;
    for (size_t k = 1; k < n; ++k) s.push_back((centre(order[k]) - centre(order[k - 1])).norm());
    return s;
  };
  const std::vector<double> name_steps = steps(by_name), block_steps = steps(by_block);
  const bool names = std::accumulate(name_steps.begin(), name_steps.end(), 0.0) <=
                     std::accumulate(block_steps.begin(), block_steps.end(), 0.0);
  std::vector<double> nearest;
  for (size_t i = 0; i < n; ++i) {
    double best = INFINITY;
    for (size_t j = 0; j < n; ++j)
      if (j != i) best = std::min(best, (centre(i) - centre(j)).norm());
    nearest.push_back(best);
  }
  if (Median(names ? name_steps : block_steps) > kOrderStep * Median(nearest)) return {};
  return names ? by_name : by_block;
}

StripDetection DetectStrips(const Block& block, const BlockGeometry* known) {
  StripDetection out;
  const size_t n = block.images.size();
  if (n == 0) return out;
  const BlockGeometry geometry = known ? *known : EstimateBlockGeometry(block);
  std::vector<double> height(n, NAN), heights;
  for (size_t i = 0; i < n; ++i) {
    const ImageGeometry& g = geometry.images[i];
    if (!geometry.aerial || !g.valid || !(g.height_above > 0)) continue;
    height[i] = g.height_above;
    heights.push_back(g.height_above);
  }
  const double median_height = Median(heights);
  auto off_height = [&](int i) {
    const double r = height[i] / median_height;
    return std::isfinite(r) && (r > kHeightRatio || r < 1 / kHeightRatio);
  };
  std::vector<int> strip_of(n, -1);
  std::vector<int> order = geometry.aerial ? FlightOrder(block) : std::vector<int>{};
  if (order.empty()) {
    std::vector<int> kept;
    for (size_t i = 0; i < n; ++i)
      if (!off_height(static_cast<int>(i))) kept.push_back(static_cast<int>(i));
    for (std::vector<int>& s : StripsFromLayout(block, kept)) {
      if (s.size() < 2) continue;  // an image alone in its heading and line
      for (const int i : s) strip_of[i] = static_cast<int>(out.strips.size());
      out.strips.push_back(std::move(s));
    }
    std::vector<int> by_index(n);
    std::iota(by_index.begin(), by_index.end(), 0);
    out.outliers = Outliers(by_index, strip_of, height, median_height);
    return out;
  }
  std::vector<Eigen::Vector2d> xy(n);
  for (size_t i = 0; i < n; ++i) xy[i] = (block.images[i].camera.center() - block.origin).head<2>();
  std::vector<int> seq;
  for (const int i : order)
    if (!off_height(i)) seq.push_back(i);
  std::vector<double> lengths;
  for (size_t k = 1; k < seq.size(); ++k) lengths.push_back((xy[seq[k]] - xy[seq[k - 1]]).norm());
  const double base = std::max(Median(lengths), 1e-9);
  const double hover = kHoverBases * base;
  std::vector<Run> runs = CutRuns(xy, seq, base);
  for (Run& r : runs) {
    r.direction = MeanStep(xy, seq, r.first, r.last, hover);
    TrimEnds(xy, seq, hover, &r);
    r.direction = MeanStep(xy, seq, r.first, r.last, hover);
  }
  for (const Run& r : StripRuns(runs)) {
    // A run that turns at an image shares it with the next: the first keeps it.
    std::vector<int> strip;
    for (size_t k = r.first; k <= r.last; ++k)
      if (strip_of[seq[k]] < 0) strip.push_back(seq[k]);
    if (strip.size() < 2) continue;
    for (const int i : strip) strip_of[i] = static_cast<int>(out.strips.size());
    out.strips.push_back(std::move(strip));
  }
  out.outliers = Outliers(order, strip_of, height, median_height);
  out.flight_order = std::move(order);
  return out;
}

}  // namespace sapmvs

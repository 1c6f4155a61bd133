// The images each group is matched in beyond its own runs: views of other
// strips, the outliers that join it, views that widen its angles.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "plan/grouping_internal.h"

namespace sapmvs {
namespace {

bool Holds(const ImageGroup& g, int i) {
  return std::find(g.images.begin(), g.images.end(), i) != g.images.end() ||
         std::find(g.views.begin(), g.views.end(), i) != g.views.end();
}

}  // namespace

// Strip groups: up to strip_views images of other strips per group, as
// views only, those that see most of the group's footprints first (summed
// OverlapShare, each at least 10 % of one group image), while the group fits
// the budget. Views are re-ranked per image when matching (SelectViews), so
// more than kMaxViews - 1 here only helps where images see different ground.
void AddStripViews(const Block& block, const GroupingOptions& o, const std::vector<Footprint>& fp,
                   GroupingPlan* plan) {
  if (o.strip_views <= 0) return;
  std::vector<int> strip_of(block.images.size(), -1);
  for (size_t s = 0; s < plan->strips.size(); ++s)
    for (const int i : plan->strips[s]) strip_of[i] = static_cast<int>(s);
  for (ImageGroup& g : plan->groups) {
    if (g.strip < 0) continue;
    std::vector<std::pair<double, int>> ranked;
    for (size_t j = 0; j < block.images.size(); ++j) {
      if (!fp[j].valid || strip_of[j] == g.strip || Holds(g, static_cast<int>(j))) {
        continue;
      }
      double sum = 0, best = 0;
      for (const int i : g.images) {
        // Disjoint bounding boxes: no overlap, without the 7 x 7 samples.
        if (!fp[i].valid || (fp[i].hi.array() < fp[j].lo.array()).any() ||
            (fp[j].hi.array() < fp[i].lo.array()).any()) {
          continue;
        }
        const double share = OverlapShare(fp, i, static_cast<int>(j));
        sum += share;
        best = std::max(best, share);
      }
      if (best >= 0.1) ranked.emplace_back(sum, static_cast<int>(j));
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    int added = 0;
    for (const auto& [share, j] : ranked) {
      if (added >= o.strip_views) break;
      ImageGroup with = g;
      with.views.push_back(j);
      if (!Fits(block, with, fp, *plan)) break;
      g.views.push_back(j);
      ++added;
    }
  }
}

std::vector<int> JoinBestGroup(const Block& block, const std::vector<Footprint>& fp,
                               const std::vector<int>& images, const std::vector<bool>& as_image,
                               GroupingPlan* plan) {
  std::vector<int> left;
  for (size_t k = 0; k < images.size(); ++k) {
    const int i = images[k];
    // The group that sees most of the image's ground, summed over its
    // images; among equals (no footprint says otherwise) the nearest.
    std::vector<std::pair<double, double>> key(plan->groups.size());
    for (size_t gi = 0; gi < plan->groups.size(); ++gi) {
      const ImageGroup& g = plan->groups[gi];
      double seen = 0;
      for (const int j : g.images) seen += OverlapShare(fp, i, j);
      key[gi] = {-seen, (g.center - fp[i].center).squaredNorm()};
    }
    std::vector<size_t> order(plan->groups.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return key[a] < key[b]; });
    if (std::any_of(plan->groups.begin(), plan->groups.end(),
                    [&](const ImageGroup& g) { return Holds(g, i); }))
      continue;
    auto fits_with = [&](const ImageGroup& g, bool as_view) {
      ImageGroup with = g;
      (as_view ? with.views : with.images).push_back(i);
      return Fits(block, with, fp, *plan);
    };
    // As an image in the group that sees most of it and has room; else as a
    // view of the one that sees most of it.
    bool joined = false;
    for (const size_t gi : order) {
      ImageGroup& g = plan->groups[gi];
      if (!as_image[k] || key[gi].first >= 0 ||
          static_cast<int>(g.images.size()) >= plan->options.max_images || !fits_with(g, false))
        continue;
      g.images.push_back(i);
      if (g.strip >= 0) g.center = MeanCenter(fp, g.images);
      joined = true;
      break;
    }
    for (size_t o = 0; o < order.size() && !joined; ++o) {
      ImageGroup& g = plan->groups[order[o]];
      if (!fits_with(g, true)) continue;
      g.views.push_back(i);
      joined = true;
    }
    if (!joined) left.push_back(i);
  }
  return left;
}

// A strip group under `smallest` images (the second run of a strip of 7 at
// --max-images 6, a short last strip that no group had room for) takes,
// as its own images, those of other groups that see most of its images'
// ground, while it has room and fits. Its centre stays, so the ground it
// owns is the same; the images only give its patches the views the paper's
// smallest group (4) has. Climb photos stay views: their GSD is not the
// strips'.
void TopUpSmallGroups(const Block& block, const std::vector<Footprint>& fp, size_t smallest,
                      GroupingPlan* plan) {
  std::vector<bool> climb(block.images.size(), false);
  for (const StripOutlier& out : plan->outliers)
    if (out.kind == OutlierKind::kClimb) climb[out.image] = true;
  for (ImageGroup& g : plan->groups) {
    while (g.images.size() < smallest &&
           static_cast<int>(g.images.size()) < plan->options.max_images) {
      int best = -1;
      std::pair<double, double> best_key{0, 0};
      for (size_t j = 0; j < block.images.size(); ++j) {
        const int v = static_cast<int>(j);
        if (climb[j] || std::find(g.images.begin(), g.images.end(), v) != g.images.end()) {
          continue;
        }
        double seen = 0;
        for (const int i : g.images) seen += OverlapShare(fp, i, v);
        const std::pair<double, double> key{seen, -(fp[j].center - g.center).squaredNorm()};
        if (seen <= 0 || (best >= 0 && key <= best_key)) continue;
        ImageGroup with = g;
        with.views.erase(std::remove(with.views.begin(), with.views.end(), v), with.views.end());
        with.images.push_back(v);
        if (!Fits(block, with, fp, *plan)) continue;
        best = v;
        best_key = key;
      }
      if (best < 0) break;
      g.views.erase(std::remove(g.views.begin(), g.views.end(), best), g.views.end());
      g.images.push_back(best);
    }
  }
}

double SpanDeg(const Block& block, const std::vector<int>& ids, const Eigen::Vector3d& x,
               double view_angle_deg) {
  const double hi = std::cos(view_angle_deg * M_PI / 180.0);
  double best = 1;
  std::vector<Eigen::Vector3d> rays;
  for (const int i : ids)
    rays.push_back((block.images[i].camera.center() - block.origin - x).normalized());
  for (size_t a = 0; a < rays.size(); ++a) {
    for (size_t b = a + 1; b < rays.size(); ++b) {
      const double c = rays[a].dot(rays[b]);
      if (c > hi && c < best) best = c;
    }
  }
  return std::acos(std::clamp(best, -1.0, 1.0)) * 180.0 / M_PI;
}

// The patches of the larger adaptive sizes need a view at 2 max_angle_deg
// from their reference (PatchEngine::WideEnough), and at short bases (4 deg
// between neighbours) a run of 6 spans 20 deg at its centre and less
// elsewhere. The views that widen it most come from the strip beyond the
// run's ends or from the strips beside it; among those that reach the
// angle, the narrowest is taken, as it sees most of the group's ground.
void AddAngleViews(const Block& block, const std::vector<Footprint>& fp, GroupingPlan* plan) {
  const double want = 2 * plan->matcher.max_angle_deg;
  const double limit = plan->matcher.view_angle_deg;
  for (ImageGroup& g : plan->groups) {
    double z = 0;
    int valid = 0;
    for (const int i : g.images) {
      if (!fp[i].valid) continue;
      z += fp[i].scene_z;
      ++valid;
    }
    if (valid == 0) continue;
    // The ground its images share: a footprint group's tile may lie at the
    // block's fringe, where no views can widen the angle.
    const Eigen::Vector2d c = MeanCenter(fp, g.images);
    const Eigen::Vector3d x(c.x(), c.y(), z / valid);
    std::vector<int> matched = g.MatchedIn();
    double span = SpanDeg(block, matched, x, limit);
    while (span < want) {
      int best = -1;
      double best_span = span;
      for (size_t j = 0; j < block.images.size(); ++j) {
        const int v = static_cast<int>(j);
        if (Holds(g, v) || !fp[j].Contains(c)) continue;
        matched.push_back(v);
        const double s = SpanDeg(block, matched, x, limit);
        matched.pop_back();
        const bool reaches = s >= want, best_reaches = best_span >= want;
        if (reaches ? (!best_reaches || s < best_span) : (!best_reaches && s > best_span)) {
          best = v;
          best_span = s;
        }
      }
      if (best < 0) break;
      ImageGroup with = g;
      with.views.push_back(best);
      if (!Fits(block, with, fp, *plan)) break;
      matched.push_back(best);
      g.views.push_back(best);
      span = best_span;
    }
  }
}

}  // namespace sapmvs

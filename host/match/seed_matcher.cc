#include "match/seed_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace sapmvs {
namespace {

// Features of one image bucketed on a coarse grid, one grid per kind, for
// radius queries: a seed's partners and supports must be of its own kind, so
// each query reads only those.
class FeatureIndex {
 public:
  // `radius` (<= kCell): the distance every query asks about.
  FeatureIndex(const std::vector<Feature>& features, int width, int height, double radius)
      : features_(features),
        cols_(width / kCell + 1),
        rows_(height / kCell + 1),
        width_(width),
        height_(height),
        radius_(radius) {
    for (KindGrid& g : grids_) {
      g.buckets.resize(static_cast<size_t>(cols_) * rows_);
      g.maybe_near.assign((static_cast<size_t>(width) * height + 63) / 64, 0);
    }
    // A point within radius of a feature has its nearest pixel centre
    // within radius + sqrt(1/2) of it.
    const double reach = radius + 0.7072;
    const int span = static_cast<int>(std::ceil(reach));
    for (size_t i = 0; i < features.size(); ++i) {
      const Feature& f = features[i];
      const int cx = std::clamp(static_cast<int>(f.uv.x()) / kCell, 0, cols_ - 1);
      const int cy = std::clamp(static_cast<int>(f.uv.y()) / kCell, 0, rows_ - 1);
      KindGrid& grid = grids_[static_cast<int>(f.kind)];
      grid.buckets[static_cast<size_t>(cy) * cols_ + cx].push_back(static_cast<int>(i));
      const int fx = static_cast<int>(std::lround(f.uv.x()));
      const int fy = static_cast<int>(std::lround(f.uv.y()));
      for (int y = std::max(fy - span, 0); y <= std::min(fy + span, height - 1); ++y) {
        for (int x = std::max(fx - span, 0); x <= std::min(fx + span, width - 1); ++x) {
          if ((Eigen::Vector2d(x, y) - f.uv).norm() <= reach) {
            const size_t bit = static_cast<size_t>(y) * width + x;
            grid.maybe_near[bit / 64] |= uint64_t{1} << (bit % 64);
          }
        }
      }
    }
  }
  // True when a feature of `kind` lies within the radius of uv.
  // The support counts asked this 92 million times on Herz-Jesu-P8 (before
  // they stopped early), nine in ten times of a point with no feature near:
  // a per-pixel mask answers those, and only the buckets the disc overlaps
  // are read for the rest.
  bool Near(const Eigen::Vector2d& uv, FeatureKind kind) const {
    const KindGrid& grid = grids_[static_cast<int>(kind)];
    // The nearest pixel, by truncation where it is on the image (std::lround
    // is a library call: an eighth of this test's time on Herz-Jesu-P8).
    if (uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < width_ - 0.5 && uv.y() < height_ - 0.5) {
      const int px = static_cast<int>(uv.x() + 0.5), py = static_cast<int>(uv.y() + 0.5);
      const size_t bit = static_cast<size_t>(py) * width_ + px;
      if (!(grid.maybe_near[bit / 64] >> (bit % 64) & 1)) return false;
    }
    const int x0 = std::max(static_cast<int>(std::floor((uv.x() - radius_) / kCell)), 0);
    const int x1 = std::min(static_cast<int>(std::floor((uv.x() + radius_) / kCell)), cols_ - 1);
    const int y0 = std::max(static_cast<int>(std::floor((uv.y() - radius_) / kCell)), 0);
    const int y1 = std::min(static_cast<int>(std::floor((uv.y() + radius_) / kCell)), rows_ - 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        for (const int i : grid.buckets[static_cast<size_t>(y) * cols_ + x]) {
          if ((features_[i].uv - uv).norm() <= radius_) return true;
        }
      }
    }
    return false;
  }
  // The indices, ascending, of every feature of `kind` that may lie within
  // the radius of the segment a-b: those in the buckets the band of that
  // radius around it overlaps, column by column along its major axis (a
  // superset; the caller applies the exact test).
  void Along(const Eigen::Vector2d& a, const Eigen::Vector2d& b, FeatureKind kind,
             std::vector<int>* out) const {
    out->clear();
    // A little wider, so that rounding in the walk never leaves out a
    // feature the exact test would take.
    const double radius = radius_ * (1 + 1e-9) + 1e-6;
    const std::vector<std::vector<int>>& buckets = grids_[static_cast<int>(kind)].buckets;
    // Only the part of the segment over the image (and `radius` around it)
    // can have features near it; clipping also bounds the walk when a
    // segment end projects far outside (Liang-Barsky).
    const double m = radius + kCell;
    const double lo[2] = {-m, -m};
    const double hi[2] = {cols_ * kCell + m, rows_ * kCell + m};
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 2; ++k) {
      const double d = b[k] - a[k];
      if (d == 0.0) {
        if (a[k] < lo[k] || a[k] > hi[k]) return;
        continue;
      }
      double ta = (lo[k] - a[k]) / d, tb = (hi[k] - a[k]) / d;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (!(t0 <= t1)) return;
    const Eigen::Vector2d from = a + t0 * (b - a), to = a + t1 * (b - a);
    if (!from.allFinite() || !to.allFinite()) return;
    // Walked one bucket line at a time across the major axis u (x or y): a
    // feature within `radius` of a point P of the segment has |u - P.u| and
    // |v - P.v| both <= radius, so in the bucket line [u0, u1) it lies
    // within `radius` across of the part of the segment whose u lies in
    // [u0 - radius, u1 + radius]. The sampled walk this replaces read 3 x 3
    // buckets every half bucket and was most of the seeds' host time.
    const int major = std::abs(to.x() - from.x()) >= std::abs(to.y() - from.y()) ? 0 : 1;
    const int minor = 1 - major;
    const int lines = major == 0 ? cols_ : rows_, across = major == 0 ? rows_ : cols_;
    const double du = to[major] - from[major];
    const double u_lo = std::min(from[major], to[major]) - radius;
    const double u_hi = std::max(from[major], to[major]) + radius;
    const int first = std::clamp(static_cast<int>(std::floor(u_lo / kCell)), 0, lines - 1);
    const int last = std::clamp(static_cast<int>(std::floor(u_hi / kCell)), 0, lines - 1);
    // The segment's minor coordinate where its major one is u, clamped to
    // its ends.
    auto minor_at = [&](double u) {
      if (du == 0.0) return from[minor];
      const double t = std::clamp((u - from[major]) / du, 0.0, 1.0);
      return from[minor] + t * (to[minor] - from[minor]);
    };
    for (int line = first; line <= last; ++line) {
      // Bucket line 0 also holds features left of 0, the last one those
      // beyond the grid (FeatureIndex clamps them in), so these reach out.
      const double l0 = line == 0 ? -std::numeric_limits<double>::infinity() : line * kCell;
      const double l1 =
          line == lines - 1 ? std::numeric_limits<double>::infinity() : (line + 1) * kCell;
      const double s0 = minor_at(std::max(l0 - radius, u_lo));
      const double s1 = minor_at(std::min(l1 + radius, u_hi));
      const double v_lo = std::min(s0, s1) - radius, v_hi = std::max(s0, s1) + radius;
      const int c0 = std::clamp(static_cast<int>(std::floor(v_lo / kCell)), 0, across - 1);
      const int c1 = std::clamp(static_cast<int>(std::floor(v_hi / kCell)), 0, across - 1);
      for (int c = c0; c <= c1; ++c) {
        const int x = major == 0 ? line : c, y = major == 0 ? c : line;
        const std::vector<int>& bucket = buckets[static_cast<size_t>(y) * cols_ + x];
        out->insert(out->end(), bucket.begin(), bucket.end());
      }
    }
    std::sort(out->begin(), out->end());
  }

 private:
  // One kind's features.
  struct KindGrid {
    std::vector<std::vector<int>> buckets;
    // A bit per pixel: 0 = no feature within radius_ of any point whose
    // nearest pixel this is (200 kB for 1536 x 1024 pixels).
    std::vector<uint64_t> maybe_near;
  };

  static constexpr int kCell = 8;
  const std::vector<Feature>& features_;
  int cols_, rows_;
  int width_, height_;
  double radius_;
  KindGrid grids_[2];  // by FeatureKind: Harris, DoG
};

// A partner's triangulated point and rank; the candidate itself is built
// only for the few that are kept (of 130 per feature on Herz-Jesu-P8).
struct Scored {
  Eigen::Vector3d x;
  int view = -1;  // the partner's image
  int support = 0;
  double epipolar = 0;
};

// Ranked best first: by support, then distance from the epipolar line (ties
// keep the order of the partner search: view, then feature index).
bool Better(const Scored& p, const Scored& q) {
  return p.support != q.support ? p.support > q.support : p.epipolar < q.epipolar;
}

}  // namespace

Eigen::Vector3d TriangulateMidpoint(const Camera& a, const Eigen::Vector2d& uv_a, const Camera& b,
                                    const Eigen::Vector2d& uv_b) {
  const Eigen::Vector3d da = a.Ray(uv_a), db = b.Ray(uv_b);
  const Eigen::Vector3d w = a.center() - b.center();
  const double aa = da.dot(da), ab = da.dot(db), bb = db.dot(db), aw = da.dot(w), bw = db.dot(w);
  const double den = aa * bb - ab * ab;
  if (!(std::abs(den) > 1e-12))
    return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  const double s = (ab * bw - bb * aw) / den;
  const double t = (aa * bw - ab * aw) / den;
  return 0.5 * ((a.center() + s * da) + (b.center() + t * db));
}

std::vector<SeedFeature> MatchSeeds(const MatchGroupData& group,
                                    const std::vector<std::vector<Feature>>& features,
                                    const MatcherOptions& options,
                                    const std::function<bool(int, const Feature&)>& wanted) {
  const int n = static_cast<int>(group.images.size());
  std::vector<FeatureIndex> index;
  index.reserve(n);
  for (int i = 0; i < n; ++i) {
    index.emplace_back(features[i], group.images[i].camera.width(), group.images[i].camera.height(),
                       options.epipolar_distance);
  }
  // Every reference feature of every image in one loop: one loop per image
  // left a core idle at each image's tail.
  std::vector<std::pair<int, int>> work;  // (image, feature), in seed order
  for (int i = 0; i < n; ++i) {
    if (!group.images[i].reference) continue;  // its features are partners only
    for (size_t fi = 0; fi < features[i].size(); ++fi) {
      if (!wanted || wanted(i, features[i][fi])) work.emplace_back(i, static_cast<int>(fi));
    }
  }
  std::vector<SeedFeature> local(work.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (size_t w = 0; w < work.size(); ++w) {
    const int i = work[w].first;
    const MatchImage& ref = group.images[i];
    const Feature& f = features[i][work[w].second];
    thread_local std::vector<Scored> scored;
    scored.clear();
    thread_local std::vector<int> near_segment;
    const Eigen::Vector3d near_point = ref.camera.BackProject(f.uv, kSeedDepthMin * ref.depth);
    const Eigen::Vector3d far_point = ref.camera.BackProject(f.uv, kSeedDepthMax * ref.depth);
    for (const int j : ref.views) {
      const Camera& cam = group.images[j].camera;
      if (!(cam.Depth(near_point) > 0) || !(cam.Depth(far_point) > 0)) continue;
      const Eigen::Vector2d a = cam.Project(near_point), b = cam.Project(far_point);
      const Eigen::Vector2d dir = b - a;
      const double len2 = dir.squaredNorm();
      if (!(len2 > 1e-12)) continue;
      // Only the features near the segment, in index order as a scan of
      // all of them met them (the ranking below keeps ties in that order):
      // the scan cost features x features per pair of images, 22 s of
      // host time on Herz-Jesu-P8 at level 1.
      index[j].Along(a, b, f.kind, &near_segment);
      for (const int gi : near_segment) {
        const Feature& g = features[j][gi];  // of f's kind
        const double t = (g.uv - a).dot(dir) / len2;
        if (t < 0 || t > 1) continue;
        const double dist = (g.uv - (a + t * dir)).norm();
        if (dist > options.epipolar_distance) continue;
        const Eigen::Vector3d x = TriangulateMidpoint(ref.camera, f.uv, cam, g.uv);
        if (!x.allFinite()) continue;
        const double depth = ref.camera.Depth(x);
        if (depth < kSeedDepthMin * ref.depth || depth > kSeedDepthMax * ref.depth) continue;
        Scored s;
        s.x = x;
        s.view = j;
        s.epipolar = dist;
        scored.push_back(s);
      }
    }
    // The support of s (views other than its partner's with a feature of
    // f's kind within epipolar_distance of its projection), or less than
    // `need` once the views left cannot bring it there.
    auto support_of = [&](const Scored& s, int need) {
      int support = 0;
      int left = static_cast<int>(ref.views.size()) - 1;  // s.view is one of them
      for (const int k : ref.views) {
        if (k == s.view) continue;
        --left;
        const Eigen::Vector2d uv = group.images[k].camera.Project(s.x);  // NaN behind it
        if (!std::isnan(uv.x()) && index[k].Near(uv, f.kind)) ++support;
        if (support + left < need) break;
      }
      return support;
    };
    // Only the best `keep` are wanted, and the support counts are most of
    // the work left (92 million projections and lookups on Herz-Jesu-P8
    // when every count ran to the end). Once `keep` are held, a partner must
    // rank above the last of them: its count stops as soon as the views
    // left cannot bring it there.
    const size_t keep = static_cast<size_t>(std::max(options.candidates_per_feature, 1));
    size_t held = 0;  // scored[0, held): the best so far, ranked
    for (size_t c = 0; c < scored.size(); ++c) {
      Scored s = scored[c];
      int need = 0;
      if (held == keep) {
        // It comes after the last held in the search, so it must be nearer
        // the line to win on equal support.
        const Scored& last = scored[keep - 1];
        need = last.support + (s.epipolar < last.epipolar ? 0 : 1);
      }
      s.support = support_of(s, need);
      if (held == keep && !Better(s, scored[keep - 1])) continue;
      size_t at = std::min(held, keep - 1);
      for (; at > 0 && Better(s, scored[at - 1]); --at) scored[at] = scored[at - 1];
      scored[at] = s;
      held = std::min(held + 1, keep);
    }
    scored.resize(held);
    SeedFeature& out = local[w];
    out.image = i;
    out.uv = f.uv;
    for (const Scored& s : scored) {  // at most `keep`, best first
      PatchCandidate c;
      c.center = s.x;
      c.normal = (ref.camera.center() - s.x).normalized();
      c.ref = i;
      out.candidates.push_back(c);
    }
  }
  std::vector<SeedFeature> seeds;
  for (SeedFeature& s : local) {
    if (!s.candidates.empty()) seeds.push_back(std::move(s));
  }
  return seeds;
}

}  // namespace sapmvs

#include "match/seed_matcher.h"

#include <algorithm>
#include <climits>
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
  // The support counts ask this 92 million times on Herz-Jesu-P8, nine in
  // ten times of a point with no feature near: a per-pixel mask answers
  // those, and only the buckets the disc overlaps are read for the rest.
  bool Near(const Eigen::Vector2d& uv, FeatureKind kind) const {
    const KindGrid& grid = grids_[static_cast<int>(kind)];
    const int px = static_cast<int>(std::lround(uv.x()));
    const int py = static_cast<int>(std::lround(uv.y()));
    if (px >= 0 && py >= 0 && px < width_ && py < height_) {
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
  // the radius of the segment a-b: those in the buckets within reach of
  // points sampled along it whose square comes within the radius of its line
  // (a superset; the caller applies the exact test).
  // `seen` is the caller's scratch (one per thread): a visit stamp per
  // bucket, so that buckets reached from several samples count once.
  struct Scratch {
    std::vector<uint32_t> seen;
    uint32_t stamp = 0;
  };
  void Along(const Eigen::Vector2d& a, const Eigen::Vector2d& b, FeatureKind kind, Scratch* scratch,
             std::vector<int>* out) const {
    out->clear();
    const double radius = radius_;
    const std::vector<std::vector<int>>& buckets = grids_[static_cast<int>(kind)].buckets;
    if (scratch->seen.size() != buckets.size() || scratch->stamp == UINT32_MAX) {
      scratch->seen.assign(buckets.size(), 0);
      scratch->stamp = 0;
    }
    const uint32_t stamp = ++scratch->stamp;
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
    const double length = (to - from).norm();
    // The line's unit normal: a bucket whose four corners all lie farther
    // than `radius` on one side holds no feature near the segment. Two thirds
    // of the 3 x 3 buckets around each sample are such (a band 2 radius wide
    // across buckets of kCell).
    Eigen::Vector2d normal(a.y() - b.y(), b.x() - a.x());
    const double normal_length = normal.norm();
    const bool prune = normal_length > 0 && std::isfinite(normal_length);
    if (prune) normal /= normal_length;
    const double reach_off = radius * (1 + 1e-9) + 1e-9;
    auto off_line = [&](int x, int y) {
      if (!prune) return false;
      const Eigen::Vector2d corner(x * kCell - a.x(), y * kCell - a.y());
      const double d0 = normal.dot(corner);
      const double dx = normal.x() * kCell, dy = normal.y() * kCell;
      const double lo_d = d0 + std::min(dx, 0.0) + std::min(dy, 0.0);
      const double hi_d = d0 + std::max(dx, 0.0) + std::max(dy, 0.0);
      return lo_d > reach_off || hi_d < -reach_off;
    };
    // Samples at most half a bucket apart: every point of the segment is
    // within a quarter bucket of one, so a feature within `radius` of the
    // segment is within radius + kCell / 4 of a sample.
    const int steps = std::max(1, static_cast<int>(std::ceil(length / (0.5 * kCell))));
    const int reach = static_cast<int>(std::ceil((radius + 0.25 * kCell) / kCell));
    int last_x = INT_MIN, last_y = INT_MIN;
    for (int s = 0; s <= steps; ++s) {
      const Eigen::Vector2d q = from + (to - from) * (static_cast<double>(s) / steps);
      if (!q.allFinite()) continue;
      const int cx = static_cast<int>(std::floor(q.x() / kCell));
      const int cy = static_cast<int>(std::floor(q.y() / kCell));
      if (cx == last_x && cy == last_y) continue;
      last_x = cx;
      last_y = cy;
      for (int y = std::max(cy - reach, 0); y <= std::min(cy + reach, rows_ - 1); ++y) {
        for (int x = std::max(cx - reach, 0); x <= std::min(cx + reach, cols_ - 1); ++x) {
          const size_t c = static_cast<size_t>(y) * cols_ + x;
          if (scratch->seen[c] == stamp) continue;
          scratch->seen[c] = stamp;
          if (off_line(x, y)) continue;
          out->insert(out->end(), buckets[c].begin(), buckets[c].end());
        }
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
  int support = 0;
  double epipolar = 0;
};

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
                                    const MatcherOptions& options) {
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
    for (size_t fi = 0; fi < features[i].size(); ++fi) work.emplace_back(i, static_cast<int>(fi));
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
    thread_local FeatureIndex::Scratch scratch;
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
      // all of them met them (the sort below keeps ties in that order):
      // the scan cost features x features per pair of images, 22 s of
      // host time on Herz-Jesu-P8 at level 1.
      index[j].Along(a, b, f.kind, &scratch, &near_segment);
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
        s.epipolar = dist;
        for (const int k : ref.views) {
          if (k == j) continue;
          const Camera& ck = group.images[k].camera;
          if (!(ck.Depth(x) > 0)) continue;
          if (index[k].Near(ck.Project(x), f.kind)) ++s.support;
        }
        scored.push_back(s);
      }
    }
    std::sort(scored.begin(), scored.end(), [](const Scored& p, const Scored& q) {
      return p.support != q.support ? p.support > q.support : p.epipolar < q.epipolar;
    });
    SeedFeature& out = local[w];
    out.image = i;
    out.uv = f.uv;
    for (const Scored& s : scored) {
      if (static_cast<int>(out.candidates.size()) >= options.candidates_per_feature) break;
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

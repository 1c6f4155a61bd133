#include "match/seed_matcher.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>

namespace sapmvs {
namespace {

// Features of one image bucketed on a coarse grid for radius queries.
class FeatureIndex {
 public:
  FeatureIndex(const std::vector<Feature>& features, int width, int height)
      : features_(features), cols_(width / kCell + 1), rows_(height / kCell + 1) {
    buckets_.resize(static_cast<size_t>(cols_) * rows_);
    for (size_t i = 0; i < features.size(); ++i) {
      const int cx = std::clamp(static_cast<int>(features[i].uv.x()) / kCell, 0, cols_ - 1);
      const int cy = std::clamp(static_cast<int>(features[i].uv.y()) / kCell, 0, rows_ - 1);
      buckets_[static_cast<size_t>(cy) * cols_ + cx].push_back(static_cast<int>(i));
    }
  }
  // True when a feature of `kind` lies within `radius` (<= kCell) of uv.
  bool Near(const Eigen::Vector2d& uv, FeatureKind kind, double radius) const {
    const int cx = static_cast<int>(std::floor(uv.x() / kCell));
    const int cy = static_cast<int>(std::floor(uv.y() / kCell));
    for (int y = cy - 1; y <= cy + 1; ++y) {
      for (int x = cx - 1; x <= cx + 1; ++x) {
        if (x < 0 || y < 0 || x >= cols_ || y >= rows_) continue;
        for (const int i : buckets_[static_cast<size_t>(y) * cols_ + x]) {
          if (features_[i].kind == kind && (features_[i].uv - uv).norm() <= radius) return true;
        }
      }
    }
    return false;
  }
  // The indices, ascending, of every feature that may lie within `radius`
  // of the segment a-b: those in the buckets within reach of points sampled
  // along it (a superset; the caller applies the exact test).
  // `seen` is the caller's scratch (one per thread): a visit stamp per
  // bucket, so that buckets reached from several samples count once.
  struct Scratch {
    std::vector<uint32_t> seen;
    uint32_t stamp = 0;
  };
  void Along(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double radius, Scratch* scratch,
             std::vector<int>* out) const {
    out->clear();
    if (scratch->seen.size() != buckets_.size() || scratch->stamp == UINT32_MAX) {
      scratch->seen.assign(buckets_.size(), 0);
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
          out->insert(out->end(), buckets_[c].begin(), buckets_[c].end());
        }
      }
    }
    std::sort(out->begin(), out->end());
  }

 private:
  static constexpr int kCell = 8;
  const std::vector<Feature>& features_;
  int cols_, rows_;
  std::vector<std::vector<int>> buckets_;
};

struct Scored {
  PatchCandidate candidate;
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
    index.emplace_back(features[i], group.images[i].camera.width(),
                       group.images[i].camera.height());
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
    std::vector<Scored> scored;
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
      index[j].Along(a, b, options.epipolar_distance, &scratch, &near_segment);
      for (const int gi : near_segment) {
        const Feature& g = features[j][gi];
        if (g.kind != f.kind) continue;
        const double t = (g.uv - a).dot(dir) / len2;
        if (t < 0 || t > 1) continue;
        const double dist = (g.uv - (a + t * dir)).norm();
        if (dist > options.epipolar_distance) continue;
        const Eigen::Vector3d x = TriangulateMidpoint(ref.camera, f.uv, cam, g.uv);
        if (!x.allFinite()) continue;
        const double depth = ref.camera.Depth(x);
        if (depth < kSeedDepthMin * ref.depth || depth > kSeedDepthMax * ref.depth) continue;
        Scored s;
        s.candidate.center = x;
        s.candidate.normal = (ref.camera.center() - x).normalized();
        s.candidate.ref = i;
        s.epipolar = dist;
        for (const int k : ref.views) {
          if (k == j) continue;
          const Camera& ck = group.images[k].camera;
          if (!(ck.Depth(x) > 0)) continue;
          if (index[k].Near(ck.Project(x), f.kind, options.epipolar_distance)) ++s.support;
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
      out.candidates.push_back(s.candidate);
    }
  }
  std::vector<SeedFeature> seeds;
  for (SeedFeature& s : local) {
    if (!s.candidates.empty()) seeds.push_back(std::move(s));
  }
  return seeds;
}

}  // namespace sapmvs

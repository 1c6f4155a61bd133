#include "match/seed_matcher.h"

#include <algorithm>
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
  std::vector<SeedFeature> seeds;
  for (int i = 0; i < n; ++i) {
    const MatchImage& ref = group.images[i];
    std::vector<SeedFeature> local(features[i].size());
#pragma omp parallel for schedule(dynamic, 64)
    for (size_t fi = 0; fi < features[i].size(); ++fi) {
      const Feature& f = features[i][fi];
      std::vector<Scored> scored;
      const Eigen::Vector3d near_point = ref.camera.BackProject(f.uv, kSeedDepthMin * ref.depth);
      const Eigen::Vector3d far_point = ref.camera.BackProject(f.uv, kSeedDepthMax * ref.depth);
      for (const int j : ref.views) {
        const Camera& cam = group.images[j].camera;
        if (!(cam.Depth(near_point) > 0) || !(cam.Depth(far_point) > 0)) continue;
        const Eigen::Vector2d a = cam.Project(near_point), b = cam.Project(far_point);
        const Eigen::Vector2d dir = b - a;
        const double len2 = dir.squaredNorm();
        if (!(len2 > 1e-12)) continue;
        for (const Feature& g : features[j]) {
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
      SeedFeature& out = local[fi];
      out.image = i;
      out.uv = f.uv;
      for (const Scored& s : scored) {
        if (static_cast<int>(out.candidates.size()) >= options.candidates_per_feature) break;
        out.candidates.push_back(s.candidate);
      }
    }
    for (SeedFeature& s : local) {
      if (!s.candidates.empty()) seeds.push_back(std::move(s));
    }
  }
  return seeds;
}

}  // namespace sapmvs

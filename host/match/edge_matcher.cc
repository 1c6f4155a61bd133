#include "match/edge_matcher.h"

#include <algorithm>
#include <cmath>

#include "match/feature_detector.h"
#include "match/seed_matcher.h"

namespace sapmvs {
namespace {

// Candidates searched per edge pixel at most; a longer segment (a huge depth
// range) keeps those nearest the middle of the range.
constexpr int kMaxEdgeCandidates = 48;

// Image rows whose candidates are scored in one launch. Up to 48 candidates
// per edge pixel, all of an image at once, were the group's peak memory on
// large images (Herz-Jesu-P8, 1536 x 1024 at level 1); 32 rows keep a launch
// at a few hundred thousand candidates, plenty to fill a device.
constexpr int kEdgeRowsPerLaunch = 32;

struct EdgeQuery {
  int x, y;
  int first_patch, num_candidates;
};

// Candidates of some image rows, in row order.
struct EdgeCandidates {
  std::vector<EdgeQuery> queries;  // first_patch indexes `patches`
  std::vector<NccPatch> patches;
  std::vector<Eigen::Vector3f> points;
  std::vector<float> along;  // position along the segment, pixels of the view
  long edge_pixels = 0;

  // Appends `other`, its queries' first_patch shifted by what is here.
  void Append(const EdgeCandidates& other) {
    const int offset = static_cast<int>(patches.size());
    for (EdgeQuery q : other.queries) {
      q.first_patch += offset;
      queries.push_back(q);
    }
    patches.insert(patches.end(), other.patches.begin(), other.patches.end());
    points.insert(points.end(), other.points.begin(), other.points.end());
    along.insert(along.end(), other.along.begin(), other.along.end());
    edge_pixels += other.edge_pixels;
  }
};

// The candidates of edge pixel (x, y) of image i: the edge pixels of view j
// on its epipolar segment between depths dmin and dmax, triangulated.
void SearchEdgePixel(const MatchGroupData& group, int i, int j, const cv::Mat& view_edges, int x,
                     int y, double dmin, double dmax, int margin, EdgeCandidates* out) {
  const Camera& ref = group.images[i].camera;
  const Camera& cam = group.images[j].camera;
  ++out->edge_pixels;
  const Eigen::Vector2d uv(x, y);
  const Eigen::Vector3d p0 = ref.BackProject(uv, dmin);
  const Eigen::Vector3d p1 = ref.BackProject(uv, dmax);
  if (!(cam.Depth(p0) > 0) || !(cam.Depth(p1) > 0)) return;
  const Eigen::Vector2d a = cam.Project(p0), b = cam.Project(p1);
  const double len = (b - a).norm();
  if (!(len > 0)) return;
  const int steps = static_cast<int>(std::ceil(len * 2));
  std::vector<std::pair<double, Eigen::Vector2i>> hits;
  Eigen::Vector2i last(-1, -1);
  for (int s = 0; s <= steps; ++s) {
    const Eigen::Vector2d q = a + (b - a) * (static_cast<double>(s) / steps);
    const Eigen::Vector2i qi(static_cast<int>(std::lround(q.x())),
                             static_cast<int>(std::lround(q.y())));
    if (qi == last) continue;
    last = qi;
    if (qi.x() < margin || qi.y() < margin || qi.x() >= cam.width() - margin ||
        qi.y() >= cam.height() - margin) {
      continue;
    }
    if (view_edges.at<uint8_t>(qi.y(), qi.x())) hits.emplace_back(s * len / steps, qi);
  }
  if (hits.empty()) return;
  if (static_cast<int>(hits.size()) > kMaxEdgeCandidates) {
    std::sort(hits.begin(), hits.end(), [&](const auto& p, const auto& q) {
      return std::abs(p.first - 0.5 * len) < std::abs(q.first - 0.5 * len);
    });
    hits.resize(kMaxEdgeCandidates);
  }
  EdgeQuery query{x, y, static_cast<int>(out->patches.size()), 0};
  for (const auto& [t, qi] : hits) {
    const Eigen::Vector3d X = TriangulateMidpoint(ref, uv, cam, qi.cast<double>());
    if (!X.allFinite()) continue;
    const Eigen::Vector3d normal = (ref.center() - X).normalized();
    out->patches.push_back(MakeNccPatch(X, normal, i));
    out->points.push_back(X.cast<float>());
    out->along.push_back(static_cast<float>(t));
    ++query.num_candidates;
  }
  if (query.num_candidates > 0) out->queries.push_back(query);
}

// Scores the candidates of image i in its first view (and the best of each
// query in its second view) and marks the matched edge pixels in `map`.
void KeepMatches(const MatchGroupData& group, const MatcherOptions& options, int i,
                 const EdgeCandidates& c, PatchEngine& engine, EdgeMap* map,
                 EdgeMatchStats* stats) {
  const MatchImage& ref = group.images[i];
  std::vector<NccPair> pairs;
  for (size_t k = 0; k < c.patches.size(); ++k) {
    pairs.push_back(NccPair{static_cast<int>(k), ref.views[0]});
  }
  const std::vector<float> scores = engine.Score(c.patches, pairs);
  // Second-view confirmation of each query's best candidate, one more launch.
  std::vector<int> best(c.queries.size(), -1);
  std::vector<NccPair> confirm;
  std::vector<int> confirm_of;
  for (size_t q = 0; q < c.queries.size(); ++q) {
    const EdgeQuery& e = c.queries[q];
    int b = -1;
    for (int k = e.first_patch; k < e.first_patch + e.num_candidates; ++k) {
      if (std::isfinite(scores[k]) && (b < 0 || scores[k] > scores[b])) b = k;
    }
    if (b < 0 || scores[b] < options.threshold) continue;
    bool ambiguous = false;
    for (int k = e.first_patch; k < e.first_patch + e.num_candidates; ++k) {
      if (k != b && std::abs(c.along[k] - c.along[b]) > 2.0f && std::isfinite(scores[k]) &&
          scores[k] > scores[b] - kEdgeAmbiguity) {
        ambiguous = true;
      }
    }
    if (ambiguous) continue;
    best[q] = b;
    if (ref.views.size() > 1) {
      confirm.push_back(NccPair{b, ref.views[1]});
      confirm_of.push_back(static_cast<int>(q));
    }
  }
  const std::vector<float> second = engine.Score(c.patches, confirm);
  for (size_t k = 0; k < confirm.size(); ++k) {
    if (!(std::isfinite(second[k]) && second[k] >= options.threshold_before))
      best[confirm_of[k]] = -1;
  }
  for (size_t q = 0; q < c.queries.size(); ++q) {
    if (best[q] < 0) continue;
    const EdgeQuery& e = c.queries[q];
    map->matched.at<uint8_t>(e.y, e.x) = 255;
    map->points.emplace(e.y * ref.grey.cols + e.x, c.points[best[q]]);
    if (stats) ++stats->matched;
  }
}

}  // namespace

std::vector<EdgeMap> MatchEdges(const MatchGroupData& group, const MatcherOptions& options,
                                const std::vector<std::pair<double, double>>& depth_range,
                                PatchEngine& engine, EdgeMatchStats* stats) {
  const int n = static_cast<int>(group.images.size());
  std::vector<cv::Mat> edges(n);
  for (int i = 0; i < n; ++i) {
    edges[i] = DetectEdges(group.images[i].grey, options.canny_low, options.canny_high);
  }
  std::vector<EdgeMap> maps(n);
  const int margin = options.window_size / 2 + 1;
  // One image and kEdgeRowsPerLaunch rows at a time, each in its own
  // launches: all images' candidates at once were the group's peak memory.
  for (int i = 0; i < n; ++i) {
    const MatchImage& ref = group.images[i];
    maps[i].matched = cv::Mat::zeros(ref.grey.size(), CV_8U);
    // Named copies, not a structured binding: clang cannot capture those in
    // the OpenMP region below.
    const double dmin = depth_range[i].first;
    const double dmax = depth_range[i].second;
    if (ref.views.empty() || !(dmin < dmax)) continue;
    for (int y0 = margin; y0 < ref.grey.rows - margin; y0 += kEdgeRowsPerLaunch) {
      const int y1 = std::min(ref.grey.rows - margin, y0 + kEdgeRowsPerLaunch);
      // Rows are searched in parallel and joined in order, so the result
      // does not depend on the thread count.
      std::vector<EdgeCandidates> rows(y1 - y0);
#pragma omp parallel for schedule(dynamic, 1)
      for (int y = y0; y < y1; ++y) {
        for (int x = margin; x < ref.grey.cols - margin; ++x) {
          if (!edges[i].at<uint8_t>(y, x)) continue;
          SearchEdgePixel(group, i, ref.views[0], edges[ref.views[0]], x, y, dmin, dmax, margin,
                          &rows[y - y0]);
        }
      }
      EdgeCandidates joined;
      for (EdgeCandidates& row : rows) {
        joined.Append(row);
        row = EdgeCandidates();
      }
      if (stats) stats->edge_pixels += joined.edge_pixels;
      if (joined.queries.empty()) continue;
      KeepMatches(group, options, i, joined, engine, &maps[i], stats);
    }
  }
  return maps;
}

}  // namespace sapmvs

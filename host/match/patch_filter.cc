#include "match/patch_filter.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "match/footprint.h"
#include "match/point_neighbours.h"
#include "sapmvs/util/default_init_allocator.h"
#include "util/streamed_median.h"

namespace sapmvs {
namespace {

// Neighbours looked at per point in passes 2 and 3. With one point per
// working pixel (sapmvs) 16 reach about 2.3 pixels; with one per 2x2 cell
// (pmvs) about 4.5.
constexpr int kNeighbours = 16;

// A union-find that threads share. A root is only ever linked under a root
// of smaller index, so every parent has a smaller index than its child: no
// cycles, whatever the order of the links. The sets, which are all the
// cluster test reads, do not depend on that order.
using Parents = std::vector<std::atomic<int>>;

// The root of i's set, halving the path on the way (a parent only moves to an
// ancestor, so another thread's link never takes it out of its set).
int Find(Parents& parent, int i) {
  while (true) {
    const int p = parent[i].load(std::memory_order_relaxed);
    if (p == i) return i;
    const int gp = parent[p].load(std::memory_order_relaxed);
    if (gp != p) {
      int expected = p;
      parent[i].compare_exchange_weak(expected, gp, std::memory_order_relaxed);
    }
    i = gp;
  }
}

void Union(Parents& parent, int a, int b) {
  while (true) {
    a = Find(parent, a);
    b = Find(parent, b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    int expected = a;
    if (parent[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
  }
}

// Points per box of the visibility pass's free-space test.
constexpr size_t kFreeSpaceChunk = 128;

// Whether some point of `box` may project into [-0.5, width - 0.5) x
// [-0.5, height - 0.5) in front of `camera` (a pinhole: the image of a box
// in front of it is the hull of its corners' images). False only when it
// cannot; a pixel of margin absorbs the corners' rounding.
bool MayHold(const Camera& camera, const Eigen::AlignedBox3d& box, int width, int height) {
  int in_front = 0;
  Eigen::AlignedBox2d image;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(k));
    if (camera.Depth(corner) > 0) {
      ++in_front;
      image.extend(camera.Project(corner));
    }
  }
  if (in_front == 0) return false;
  if (in_front < 8) return true;
  constexpr double kMargin = 1.5;
  return image.max().x() >= -kMargin && image.min().x() < width + kMargin &&
         image.max().y() >= -kMargin && image.min().y() < height + kMargin;
}

}  // namespace

std::vector<bool> VisibilityFilter(const MatchGroupData& group, const MatcherOptions& options,
                                   const std::vector<DensePoint>& points,
                                   const std::vector<AcceptedPatch>& patches,
                                   const std::vector<bool>& eligible) {
  auto in = [&](size_t i) { return eligible.empty() || eligible[i]; };
  const int n = static_cast<int>(group.images.size());
  const int cs = options.cell_size;
  struct Buffer {
    int cols, rows;
    std::vector<float> min_depth, front, back;
  };
  std::vector<Buffer> buffers(n);
  for (int v = 0; v < n; ++v) {
    Buffer& b = buffers[v];
    b.cols = (group.images[v].camera.width() + cs - 1) / cs;
    b.rows = (group.images[v].camera.height() + cs - 1) / cs;
    const size_t size = static_cast<size_t>(b.cols) * b.rows;
    b.min_depth.assign(size, std::numeric_limits<float>::infinity());
    b.front.assign(size, 0);
    b.back.assign(size, 0);
  }
  // Cell and depth of point x in image v; false when x is behind the camera
  // or off the image.
  auto cell_of = [&](int v, const Eigen::Vector3d& x, size_t* cell, double* d) {
    const Camera& cam = group.images[v].camera;
    *d = cam.Depth(x);
    if (!(*d > 0)) return false;
    const Eigen::Vector2d uv = cam.Project(x);
    const int cx = static_cast<int>(std::floor((uv.x() + 0.5) / cs));
    const int cy = static_cast<int>(std::floor((uv.y() + 0.5) / cs));
    if (cx < 0 || cy < 0 || cx >= buffers[v].cols || cy >= buffers[v].rows) return false;
    *cell = static_cast<size_t>(cy) * buffers[v].cols + cx;
    return true;
  };
  // The depth tolerance of x on a plane of normal nx in image v, counted in
  // footprints along the plane's slope: a surface seen obliquely spreads its
  // depths over a cell that much further.
  auto tolerance = [&](int v, const Eigen::Vector3d& x, const Eigen::Vector3d& nx) {
    return options.depth_tolerance * SlopeFootprint(group.images[v].camera, x, nx);
  };
  // Both, for a point on a plane of normal nx.
  auto locate = [&](int v, const Eigen::Vector3d& x, const Eigen::Vector3d& nx, size_t* cell,
                    double* d, double* tol) {
    if (!cell_of(v, x, cell, d)) return false;
    *tol = tolerance(v, x, nx);
    return true;
  };
  auto weight = [&](size_t i) {
    const AcceptedPatch& p = patches[points[i].patch];
    return static_cast<float>((1 + p.views.size()) * std::max(0.0f, p.score));
  };
  // Per point: the images where it lies within the tolerance of the
  // nearest depth, and whether in one of them it hides more support than
  // lies in front.
  std::vector<int> visible(points.size(), 0);
  std::vector<uint8_t> occluding(points.size(), 0);
  // Per image, the points matched in it (reference or photo-consistent
  // view), in point order: matched[first[v] .. first[v + 1]). Listed once:
  // each image scanning every point for itself made the pass grow with
  // points x images (the filter of a group of 75 images took 52 s of its 121).
  std::vector<size_t> first(n + 1, 0);
  UninitializedVector<uint32_t> matched;
  {
    // Each thread lists a run of consecutive points; the runs are laid out
    // image by image in thread order, which is point order (listed by one
    // thread, they took 1.7 s more of that group's 38 s filter).
    std::vector<size_t> at;  // [thread * n + image]: its count, then where it writes
#pragma omp parallel
    {
      const size_t t = static_cast<size_t>(omp_get_thread_num());
      const size_t teams = static_cast<size_t>(omp_get_num_threads());
#pragma omp single
      at.assign(teams * n, 0);
      const size_t i0 = points.size() * t / teams, i1 = points.size() * (t + 1) / teams;
      size_t* mine = &at[t * n];
      for (size_t i = i0; i < i1; ++i) {
        if (!in(i)) continue;
        const AcceptedPatch& patch = patches[points[i].patch];
        ++mine[patch.ref];
        for (const int v : patch.views) ++mine[v];
      }
#pragma omp barrier
#pragma omp single
      {
        size_t total = 0;
        for (int v = 0; v < n; ++v) {
          first[v] = total;
          for (size_t u = 0; u < teams; ++u) {
            const size_t count = at[u * n + v];
            at[u * n + v] = total;
            total += count;
          }
        }
        first[n] = total;
        matched.resize(total);
      }
      for (size_t i = i0; i < i1; ++i) {
        if (!in(i)) continue;
        const AcceptedPatch& patch = patches[points[i].patch];
        matched[mine[patch.ref]++] = static_cast<uint32_t>(i);
        for (const int v : patch.views) matched[mine[v]++] = static_cast<uint32_t>(i);
      }
    }
  }
  // One thread per image fills its buffers, in point order as one thread
  // would, so the sums do not depend on the thread count (these projections
  // ran on one core while the other waited). Each point is located in the
  // image once, its cell, depth and tolerance kept for the three passes
  // over them: located in each pass, they were two thirds of the filter's
  // visibility test on Herz-Jesu-P8.
#pragma omp parallel
  {
    // The depth is computed again where needed (a dot product): kept, it
    // made the entries half as large again, and they set the group's peak
    // on Herz-Jesu-P8.
    struct Seen {
      uint32_t point, cell;
      double tolerance;
    };
    std::vector<Seen> seen;
#pragma omp for schedule(dynamic, 1)
    for (int v = 0; v < n; ++v) {
      Buffer& b = buffers[v];
      const Camera& camera = group.images[v].camera;
      // Allocated once at its size: grown by doubling, it held up to twice
      // that, and a copy beside it.
      std::vector<Seen>().swap(seen);
      seen.reserve(first[v + 1] - first[v]);
      for (size_t m = first[v]; m < first[v + 1]; ++m) {
        const uint32_t i = matched[m];
        const AcceptedPatch& patch = patches[points[i].patch];
        size_t cell = 0;
        double d = 0, tol = 0;
        if (locate(v, points[i].x, patch.normal, &cell, &d, &tol))
          seen.push_back({i, static_cast<uint32_t>(cell), tol});
      }
      auto in_front = [&](const Seen& e) {
        return camera.Depth(points[e.point].x) <= b.min_depth[e.cell] + e.tolerance;
      };
      for (const Seen& e : seen) {
        b.min_depth[e.cell] =
            std::min(b.min_depth[e.cell], static_cast<float>(camera.Depth(points[e.point].x)));
      }
      for (const Seen& e : seen)
        (in_front(e) ? b.front[e.cell] : b.back[e.cell]) += weight(e.point);
      for (const Seen& e : seen) {
        if (!in_front(e)) continue;
#pragma omp atomic
        ++visible[e.point];
        if (b.front[e.cell] < b.back[e.cell]) {
#pragma omp atomic write
          occluding[e.point] = 1;
        }
      }
    }
    std::vector<Seen>().swap(seen);
  }
  UninitializedVector<uint32_t>().swap(matched);
  // Bytes, not vector<bool>: its elements share words, and two threads
  // writing neighbouring elements could lose one of the writes.
  std::vector<uint8_t> kept(points.size(), 0);
  const size_t chunks = (points.size() + kFreeSpaceChunk - 1) / kFreeSpaceChunk;
#pragma omp parallel
  {
    // The images the point was matched in, cleared again after each point.
    std::vector<uint8_t> own(n, 0);
    std::vector<int> candidates;
    candidates.reserve(n);
#pragma omp for schedule(static)
    for (size_t chunk = 0; chunk < chunks; ++chunk) {
      const size_t i0 = chunk * kFreeSpaceChunk;
      const size_t i1 = std::min(points.size(), i0 + kFreeSpaceChunk);
      // The images whose cells the chunk's tested points may fall in:
      // projecting every point into every image made the test grow with
      // points x images. Consecutive points come from the same few patches,
      // so their box is small and most images miss it.
      Eigen::AlignedBox3d box;
      for (size_t i = i0; i < i1; ++i) {
        if (in(i) && !occluding[i]) box.extend(points[i].x);
      }
      candidates.clear();
      if (!box.isEmpty()) {
        for (int v = 0; v < n; ++v) {
          if (MayHold(group.images[v].camera, box, buffers[v].cols * cs, buffers[v].rows * cs))
            candidates.push_back(v);
        }
      }
      for (size_t i = i0; i < i1; ++i) {
        if (!in(i)) continue;
        const AcceptedPatch& patch = patches[points[i].patch];
        own[patch.ref] = 1;
        for (const int v : patch.views) own[v] = 1;
        // Free space: in an image the point was not matched in, a surface that
        // image did match lying farther along the same line of sight was seen
        // through the point, so the point floats in empty space (a window that
        // fattened a roof over the ground beside it). It goes when those
        // surfaces carry more support than it does. Only a cell with support
        // whose nearest depth lies beyond the point's can count (the tolerance
        // is >= 0), so the tolerance is computed for those alone.
        float violated = 0;
        if (!occluding[i]) {
          for (const int v : candidates) {
            size_t cell = 0;
            double d = 0;
            if (own[v] || !cell_of(v, points[i].x, &cell, &d)) continue;
            const Buffer& b = buffers[v];
            if (!(b.front[cell] > 0) || !(d < b.min_depth[cell])) continue;
            if (d < b.min_depth[cell] - tolerance(v, points[i].x, patch.normal)) {
              violated += b.front[cell];
            }
          }
        }
        own[patch.ref] = 0;
        for (const int v : patch.views) own[v] = 0;
        kept[i] = visible[i] >= options.min_image_num && !occluding[i] && violated <= weight(i);
      }
    }
  }
  return std::vector<bool>(kept.begin(), kept.end());
}

double DisparityDepth(const MatchGroupData& group, const AcceptedPatch& patch) {
  const Eigen::Vector3d& x = patch.center;
  const Camera& ref = group.images[patch.ref].camera;
  const Eigen::Vector3d ray = (ref.center() - x).normalized();
  double best = std::numeric_limits<double>::infinity();
  for (const int v : patch.views) {
    const Camera& view = group.images[v].camera;
    const double sine = ray.cross((view.center() - x).normalized()).norm();
    if (sine > 0) best = std::min(best, Footprint(view, x) / sine);
  }
  return best / Footprint(ref, x);
}

std::vector<bool> FilterPoints(const MatchGroupData& group, const MatcherOptions& options,
                               const std::vector<DensePoint>& points,
                               const std::vector<AcceptedPatch>& patches, MatchStats* stats,
                               const PatchClasses& classes, FilterTests tests) {
  std::vector<bool> eligible(points.size());
  long low = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    eligible[i] = patches[points[i].patch].score >= classes.FloorOf(points[i].patch);
    low += !eligible[i];
  }
  stats->removed_score = low;
  std::vector<bool> keep = VisibilityFilter(group, options, points, patches, eligible);
  std::vector<int> alive;
  alive.reserve(std::count(keep.begin(), keep.end(), true));
  for (size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) alive.push_back(static_cast<int>(i));
  }
  stats->removed_visibility = static_cast<long>(points.size() - alive.size()) - low;
  if (alive.empty() || tests == FilterTests::kScoreAndVisibility) return keep;

  // nn[a * k + j]: the row of the j-th nearest neighbour of row a's point
  // (alive[a]) within a's radius, neighbour_radius footprints along its
  // plane's slope, so that a surface seen obliquely, whose points lie
  // further apart, keeps as many neighbours as one seen face-on; or -1.
  const int k = kNeighbours;
  UninitializedVector<int32_t> nn;
  {
    std::vector<float> xyz(alive.size() * 3);
    std::vector<double> radius(alive.size());
#pragma omp parallel for schedule(static)
    for (size_t a = 0; a < alive.size(); ++a) {
      const DensePoint& p = points[alive[a]];
      const AcceptedPatch& patch = patches[p.patch];
      const Camera& camera = group.images[patch.ref].camera;
      for (int c = 0; c < 3; ++c) xyz[3 * a + c] = static_cast<float>(p.x[c]);
      radius[a] = options.neighbour_radius * SlopeFootprint(camera, p.x, patch.normal);
    }
    // Rows in the grid's order: each point's neighbours are then rows near
    // its own, and the reads through them below stay in cache (in the
    // points' order they were a cache miss each).
    std::vector<int32_t> order;
    nn = NearestWithin(std::move(xyz), radius, k, &order);
    std::vector<int> by_row(alive.size());
    for (size_t r = 0; r < alive.size(); ++r) by_row[r] = alive[order[r]];
    alive.swap(by_row);
  }
  // What the tests below read of each row's point and its neighbours', in
  // the rows' order.
  struct RowPoint {
    Eigen::Vector3d x;
    int patch;
  };
  UninitializedVector<RowPoint> row(alive.size());
#pragma omp parallel for schedule(static)
  for (size_t a = 0; a < alive.size(); ++a) row[a] = {points[alive[a]].x, points[alive[a]].patch};
  // Row a's point's footprint in its reference image, the unit of the plane
  // distances below: computed once per row where a loop needs it rather
  // than stored, which beside `nn` and `row` raised the filter's peak.
  auto footprint = [&](size_t a) {
    return Footprint(group.images[patches[row[a].patch].ref].camera, row[a].x);
  };
  // The distances, in footprints, from the plane of row a's patch to its k
  // neighbours, each NaN where the neighbour belongs to the same patch or
  // there is none: the plane tolerance and test 2b below both come from
  // these. Computed where needed rather than stored: kept, they were as
  // large as `nn`.
  auto foreign_distances = [&](size_t a, float* out) {
    const RowPoint& p = row[a];
    const AcceptedPatch& patch = patches[p.patch];
    const double fp = footprint(a);
    for (int j = 0; j < k; ++j) {
      const int32_t b = nn[a * k + j];
      out[j] = std::nanf("");
      if (b < 0 || row[b].patch == p.patch) continue;
      out[j] = static_cast<float>(std::abs(patch.normal.dot(row[b].x - patch.center)) / fp);
    }
  };
  // The plane tolerance: at least plane_tolerance footprints, else
  // plane_sigmas robust standard deviations of those distances (1.4826 x
  // their median, as for half-normal residuals). Depth noise between patches
  // differs with texture and geometry (median 0.18 footprints on the
  // simulator's `small`, 0.43 on NGI's scans); one fixed tolerance either lets
  // roof planes stray over the ground on the one or strips the other.
  double tolerance = options.plane_tolerance;
  const float median = StreamedMedianOfRows(alive.size(), k, foreign_distances);
  if (!std::isnan(median)) tolerance = std::max(tolerance, options.plane_sigmas * 1.4826 * median);
  stats->plane_tolerance = tolerance;

  // 2. Neighbourhood and local plane. A pmvs pass's one-cell patch whose
  // views resolve its depth to within pmvs_pass_plane_tolerance may lie that
  // far off the plane (MatcherOptions::pmvs_pass_plane_tolerance).
  std::vector<uint8_t> pass(alive.size(), 0);
#pragma omp parallel for schedule(static)
  for (size_t a = 0; a < alive.size(); ++a) {
    const RowPoint& p = row[a];
    const double fp = footprint(a);
    // The neighbours in nn's order, without a per-point allocation.
    int count = 0;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int j = 0; j < k; ++j) {
      const int32_t b = nn[a * k + j];
      if (b < 0) continue;
      mean += row[b].x;
      ++count;
    }
    if (count < options.min_neighbours) continue;
    mean /= static_cast<double>(count);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int j = 0; j < k; ++j) {
      const int32_t b = nn[a * k + j];
      if (b < 0) continue;
      const Eigen::Vector3d d = row[b].x - mean;
      cov += d * d.transpose();
    }
    // The closed form: Eigen's iterative solver was 2.5 % of Herz-Jesu-P8's
    // CPU samples, and the filter took 0.4-0.5 s longer with it. Only a
    // nearly isotropic neighbourhood, whose normal means nothing, may come
    // out differently (one point of 188,360 on `small`).
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(cov);
    const Eigen::Vector3d normal = es.eigenvectors().col(0);
    double within = tolerance;
    if (classes.OneCell(p.patch) && options.pmvs_pass_plane_tolerance > tolerance &&
        DisparityDepth(group, patches[p.patch]) <= options.pmvs_pass_plane_tolerance) {
      within = options.pmvs_pass_plane_tolerance;
    }
    pass[a] = std::abs(normal.dot(p.x - mean)) <= within * fp;
  }
  // 2b. Patch support: the points of other patches next to a patch must lie
  // on its plane. A sapmvs patch emits hundreds of points on one plane, which
  // all pass test 2 among themselves however wrong the plane is; its
  // neighbours are the independent evidence. A majority is asked for, not
  // all, so a roof patch survives ground neighbours along its edge.
  // Not a pmvs pass's one-cell patch: it emits its centre only, which test
  // 2 judges, and its plane is what a window_size window cannot pin down
  // where it straddles an edge. A wall of `small` is under 7 pixels wide in
  // a nadir image within 21 degrees of the nadir, and PMVS2's points on it
  // come from patches whose normals lie a median 45 degrees off the wall's:
  // this test dropped ours (77 % of PMVS2's right points that ours missed
  // lay on walls). Their depth is pinned instead by a view at least 2
  // max_angle_deg from their reference (PatchEngine::Role::kOneCellPass).
  std::vector<int> foreign(patches.size(), 0), consistent(patches.size(), 0);
#pragma omp parallel for schedule(static)
  for (size_t a = 0; a < alive.size(); ++a) {
    const int id = row[a].patch;
    int f = 0, c = 0;
    std::array<float, kNeighbours> distances;
    foreign_distances(a, distances.data());
    for (const float d : distances) {
      if (std::isnan(d)) continue;
      ++f;
      c += d <= tolerance;
    }
    if (f == 0) continue;
#pragma omp atomic
    foreign[id] += f;
#pragma omp atomic
    consistent[id] += c;
  }
  auto supported = [&](int id) {
    if (classes.OneCell(id)) return true;
    return foreign[id] >= options.min_neighbours && 2 * consistent[id] >= foreign[id];
  };
  long removed_plane = 0;
  for (size_t a = 0; a < alive.size(); ++a) {
    if (pass[a] && !supported(row[a].patch)) pass[a] = 0;
    if (!pass[a]) {
      keep[alive[a]] = false;
      ++removed_plane;
    }
  }
  stats->removed_neighbourhood = removed_plane;
  // The clusters read the table alone: their arrays take row's place.
  UninitializedVector<RowPoint>().swap(row);

  // 3. Small clusters among the survivors.
  const long n_alive = static_cast<long>(alive.size());
  Parents parent(alive.size());
  for (long a = 0; a < n_alive; ++a)
    parent[a].store(static_cast<int>(a), std::memory_order_relaxed);
#pragma omp parallel for schedule(static)
  for (long a = 0; a < n_alive; ++a) {
    if (!pass[a]) continue;
    for (int j = 0; j < k; ++j) {
      const int32_t b = nn[a * k + j];
      if (b >= 0 && pass[b]) Union(parent, static_cast<int>(a), b);
    }
  }
  std::vector<int> root(alive.size(), -1);
#pragma omp parallel for schedule(static)
  for (long a = 0; a < n_alive; ++a) {
    if (pass[a]) root[a] = Find(parent, static_cast<int>(a));
  }
  std::vector<int> size(alive.size(), 0);
  for (long a = 0; a < n_alive; ++a) {
    if (pass[a]) ++size[root[a]];
  }
  long removed_clusters = 0;
  for (long a = 0; a < n_alive; ++a) {
    if (pass[a] && size[root[a]] < options.min_cluster_size) {
      keep[alive[a]] = false;
      ++removed_clusters;
    }
  }
  stats->removed_clusters = removed_clusters;
  return keep;
}

double ScoreFloor(const MatcherOptions& options, const std::vector<DensePoint>& points,
                  const std::vector<AcceptedPatch>& patches, size_t first_patch) {
  double floor = options.threshold;
  std::vector<double> s;
  if (options.score_fence > 0) {
    for (const DensePoint& d : points) {
      if (static_cast<size_t>(d.patch) >= first_patch) s.push_back(patches[d.patch].score);
    }
  }
  if (s.size() >= 10) {
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    const double median = s[s.size() / 2];
    for (double& v : s) v = std::abs(v - median);
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    const double sigma = 1.4826 * s[s.size() / 2];
    floor = std::max(options.threshold, median - options.score_fence * sigma);
  }
  return floor;
}

std::vector<std::pair<double, double>> SeedDepthFences(
    const std::vector<std::vector<double>>& seed_depths, const std::vector<double>& search_near,
    double gsd) {
  std::vector<std::pair<double, double>> fences(seed_depths.size(), {0.0, 0.0});
  for (size_t i = 0; i < seed_depths.size(); ++i) {
    std::vector<double> d = seed_depths[i];
    if (d.size() < 10) continue;
    std::sort(d.begin(), d.end());
    const double q1 = d[d.size() / 4], q3 = d[(3 * d.size()) / 4];
    const double pad = 3.0 * (q3 - q1) + 10.0 * gsd;
    const double tukey_near = q1 - pad;
    const double near = i < search_near.size() && search_near[i] > 0
                            ? std::min(tukey_near, search_near[i])
                            : tukey_near;
    fences[i] = {near, q3 + pad};
  }
  return fences;
}

long ApplyDepthFences(const MatchGroupData& group, const std::vector<DensePoint>& points,
                      const std::vector<AcceptedPatch>& patches,
                      const std::vector<std::pair<double, double>>& fences,
                      std::vector<bool>* keep) {
  // vector<bool> packs its elements into shared words, so the threads only
  // decide; the writes stay on one.
  const long n = static_cast<long>(points.size());
  std::vector<uint8_t> out(points.size(), 0);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    if (!(*keep)[i]) continue;
    const int ref = patches[points[i].patch].ref;
    const auto [lo, hi] = fences[ref];
    if (lo == 0 && hi == 0) continue;
    const double depth = group.images[ref].camera.Depth(points[i].x);
    out[i] = depth < lo || depth > hi;
  }
  long removed = 0;
  for (long i = 0; i < n; ++i) {
    if (!out[i]) continue;
    (*keep)[i] = false;
    ++removed;
  }
  return removed;
}

}  // namespace sapmvs

#include "match/point_neighbours.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <utility>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// A grid column has a cell per `cell` along the cloud's two widest axes; at
// most this many columns per point (plus a floor for tiny clouds), so that a
// sparse cloud over a wide block does not allocate a column per empty cell.
constexpr size_t kColumnsPerPoint = 4;
constexpr size_t kMinColumns = 1024;

// A point in a column, with its cell along the column.
struct Entry {
  float x, y, z;
  int32_t w;
  int32_t index;
};

// The squared distance exactly as FLANN's L2<float> summed it (query minus
// point, x then y then z), so that a neighbour at the radius is in or out as
// it was.
inline float SquaredDistance(const float* q, const Entry& e) {
  float d2 = 0;
  const float dx = q[0] - e.x, dy = q[1] - e.y, dz = q[2] - e.z;
  d2 += dx * dx;
  d2 += dy * dy;
  d2 += dz * dz;
  return d2;
}

// A neighbour as one key that orders as (squared distance, index): the
// distance's bits above the index. A float >= 0 orders as its bits read as
// an unsigned integer (the squared distance is a sum of squares, never -0).
inline uint64_t Key(float d2, int32_t index) {
  uint32_t bits;
  std::memcpy(&bits, &d2, sizeof bits);
  return static_cast<uint64_t>(bits) << 32 | static_cast<uint32_t>(index);
}

inline float KeyDistance(uint64_t key) {
  const uint32_t bits = static_cast<uint32_t>(key >> 32);
  float d2;
  std::memcpy(&d2, &bits, sizeof d2);
  return d2;
}

// The lowest and highest coordinate of the points on each axis.
std::pair<std::array<double, 3>, std::array<double, 3>> Bounds(const std::vector<float>& xyz) {
  std::array<double, 3> lo, hi;
  lo.fill(std::numeric_limits<double>::infinity());
  hi.fill(-std::numeric_limits<double>::infinity());
  for (size_t a = 0; a < xyz.size() / 3; ++a) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], static_cast<double>(xyz[3 * a + c]));
      hi[c] = std::max(hi[c], static_cast<double>(xyz[3 * a + c]));
    }
  }
  return {lo, hi};
}

class ColumnGrid {
 public:
  ColumnGrid(const std::vector<float>& xyz, double cell_hint) {
    const size_t n = xyz.size() / 3;
    const auto bounds = Bounds(xyz);
    const std::array<double, 3>& lo = bounds.first;
    const std::array<double, 3>& hi = bounds.second;
    // The column runs along the axis the cloud spans least: a terrain's
    // height, a facade's depth.
    std::array<int, 3> axes = {0, 1, 2};
    std::sort(axes.begin(), axes.end(),
              [&](int a, int b) { return hi[a] - lo[a] > hi[b] - lo[b]; });
    u_ = axes[0], v_ = axes[1], w_ = axes[2];
    lo_ = lo;
    const double eu = hi[u_] - lo[u_], ev = hi[v_] - lo[v_];
    // Column numbers are int32 (NearestWithin allows up to 2^31 - 1 points,
    // four columns each would not fit).
    const double max_columns =
        std::min(static_cast<double>(std::max(kColumnsPerPoint * n, kMinColumns)),
                 static_cast<double>(std::numeric_limits<int32_t>::max()));
    cell_ = cell_hint > 0 ? cell_hint : std::max({eu, ev, hi[w_] - lo[w_], 1.0});
    cell_ = std::max(cell_, std::sqrt(eu * ev / max_columns));
    while ((std::floor(eu / cell_) + 1) * (std::floor(ev / cell_) + 1) > max_columns) cell_ *= 1.25;
    nu_ = static_cast<int>(std::floor(eu / cell_)) + 1;
    nv_ = static_cast<int>(std::floor(ev / cell_)) + 1;
    nw_ = static_cast<int>(std::min(std::floor((hi[w_] - lo[w_]) / cell_) + 1, 1e9));

    // Counting sort by column, then each column by (cell along it, index).
    UninitializedVector<int32_t> column(n);
    start_.assign(static_cast<size_t>(nu_) * nv_ + 1, 0);
    for (size_t a = 0; a < n; ++a) {
      const float* p = &xyz[3 * a];
      column[a] = Cell(p[u_], u_, nu_) * nv_ + Cell(p[v_], v_, nv_);
      ++start_[column[a] + 1];
    }
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    entries_.resize(n);
    std::vector<uint32_t> fill(start_.begin(), start_.end() - 1);
    for (size_t a = 0; a < n; ++a) {
      const float* p = &xyz[3 * a];
      entries_[fill[column[a]]++] =
          Entry{p[0], p[1], p[2], Cell(p[w_], w_, nw_), static_cast<int32_t>(a)};
    }
    const long columns = static_cast<long>(start_.size()) - 1;
#pragma omp parallel for schedule(dynamic, 256)
    for (long c = 0; c < columns; ++c) {
      std::sort(entries_.begin() + start_[c], entries_.begin() + start_[c + 1],
                [](const Entry& a, const Entry& b) {
                  return a.w != b.w ? a.w < b.w : a.index < b.index;
                });
    }
  }

  // Writes to `out` (k slots) the at most k points nearest to p, other than
  // point `self`, whose squared distance is at most r2, nearest first (ties
  // by index); the rest -1. Columns are visited in rings around p's and
  // skipped once they lie farther than the k-th point found, so that a
  // point among many others reads little more than its own ring. `best` is
  // the caller's scratch (one per thread).
  void Nearest(const float* p, int32_t self, float r2, double reach, int k, int32_t* out,
               std::vector<uint64_t>* best) const {
    best->resize(k);
    uint64_t* held = best->data();
    int count = 0;
    // The bar a point must pass: within the radius, and once k are held,
    // no farther than the farthest of them (a tie then goes by index).
    float bar = r2;
    const int u0 = Cell(p[u_] - reach, u_, nu_), u1 = Cell(p[u_] + reach, u_, nu_);
    const int v0 = Cell(p[v_] - reach, v_, nv_), v1 = Cell(p[v_] + reach, v_, nv_);
    const int w0 = Cell(p[w_] - reach, w_, nw_), w1 = Cell(p[w_] + reach, w_, nw_);
    const int cu = Cell(p[u_], u_, nu_), cv = Cell(p[v_], v_, nv_);
    const int rings = std::max({cu - u0, u1 - cu, cv - v0, v1 - cv});
    auto visit = [&](int iu, int iv) {
      if (count == k) {
        // The column's nearest possible point, a little nearer than exact,
        // so that rounding never skips a point that would have counted.
        const double du =
            std::max({0.0, lo_[u_] + iu * cell_ - p[u_], p[u_] - (lo_[u_] + (iu + 1) * cell_)});
        const double dv =
            std::max({0.0, lo_[v_] + iv * cell_ - p[v_], p[v_] - (lo_[v_] + (iv + 1) * cell_)});
        if ((du * du + dv * dv) * (1 - 1e-5) > KeyDistance(held[k - 1])) return;
      }
      const size_t c = static_cast<size_t>(iu) * nv_ + iv;
      auto it = entries_.begin() + start_[c];
      const auto end = entries_.begin() + start_[c + 1];
      if (it == end) return;
      it = std::lower_bound(it, end, w0, [](const Entry& e, int w) { return e.w < w; });
      for (; it != end && it->w <= w1; ++it) {
        const float d2 = SquaredDistance(p, *it);
        if (!(d2 <= bar) || it->index == self) continue;
        const uint64_t key = Key(d2, it->index);
        int at = count;
        if (count == k) {
          if (key > held[k - 1]) continue;
          at = k - 1;
        } else {
          ++count;
        }
        // Insertion from the back: most points that get in are among the
        // farthest held.
        for (; at > 0 && held[at - 1] > key; --at) held[at] = held[at - 1];
        held[at] = key;
        if (count == k) bar = std::min(r2, KeyDistance(held[k - 1]));
      }
    };
    for (int ring = 0; ring <= rings; ++ring) {
      for (int iu = std::max(u0, cu - ring); iu <= std::min(u1, cu + ring); ++iu) {
        const bool edge_u = iu == cu - ring || iu == cu + ring;
        for (int iv = std::max(v0, cv - ring); iv <= std::min(v1, cv + ring); ++iv) {
          // Only the ring's own columns: its first and last rows whole, the
          // others at their two ends.
          if (!edge_u && iv != cv - ring && iv != cv + ring) {
            if (iv < cv + ring) iv = cv + ring - 1;
            continue;
          }
          visit(iu, iv);
        }
      }
    }
    for (int j = 0; j < count; ++j) out[j] = static_cast<int32_t>(held[j] & 0xffffffffu);
    std::fill(out + count, out + k, -1);
  }

  // The e-th point in column order.
  const Entry& entry(size_t e) const { return entries_[e]; }

 private:
  int Cell(double x, int axis, int cells) const {
    const double c = std::floor((x - lo_[axis]) / cell_);
    return static_cast<int>(std::clamp(c, 0.0, static_cast<double>(cells - 1)));
  }

  std::array<double, 3> lo_{};
  int u_ = 0, v_ = 1, w_ = 2;
  double cell_ = 1;
  int nu_ = 1, nv_ = 1, nw_ = 1;
  std::vector<uint32_t> start_;         // column c's entries: [start_[c], start_[c + 1])
  UninitializedVector<Entry> entries_;  // every one written by the constructor
};

}  // namespace

UninitializedVector<int32_t> NearestWithin(std::vector<float> xyz,
                                           const std::vector<double>& radius, int k,
                                           std::vector<int32_t>* order) {
  const size_t n = radius.size();
  if (xyz.size() != 3 * n) {
    throw Error("NearestWithin: expected 3 coordinates per radius (" + std::to_string(xyz.size()) +
                " coordinates, " + std::to_string(n) + " radii)");
  }
  if (k < 1) throw Error("NearestWithin: expected k >= 1 (k = " + std::to_string(k) + ")");
  if (n > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    throw Error("NearestWithin: " + std::to_string(n) +
                " points, more than an int32 index holds (2^31 - 1)");
  }
  for (const double r : radius) {
    if (!(r >= 0 && std::isfinite(r))) {
      throw Error("NearestWithin: expected finite radii >= 0 (radius = " + std::to_string(r) + ")");
    }
  }
  if (n == 0) return {};
  // Half the median radius: the cells a radius reaches (about 5 x 5
  // columns) then hold a few points each.
  double median = 0;
  {
    std::vector<double> sorted = radius;
    std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
    median = sorted[n / 2];
  }
  auto grid = std::make_unique<const ColumnGrid>(xyz, 0.5 * median);
  // The grid's entries hold the coordinates from here on. The output, four
  // times their size at k = 16, is only allocated once the input is gone:
  // this is the peak of the filter, which is the peak of a group's run.
  std::vector<float>().swap(xyz);  // `xyz = {}` would keep the capacity
  if (order) {
    order->resize(n);
    for (size_t e = 0; e < n; ++e) (*order)[e] = grid->entry(e).index;
  }
  // Each row is written whole by the thread that searches its point, which
  // so takes its pages' first faults.
  UninitializedVector<int32_t> out(n * static_cast<size_t>(k));

#pragma omp parallel
  {
    std::vector<uint64_t> best;
    // In the grid's order, so that consecutive queries read the same columns.
#pragma omp for schedule(dynamic, 512)
    for (size_t e = 0; e < n; ++e) {
      const Entry& entry = grid->entry(e);
      const float q[3] = {entry.x, entry.y, entry.z};
      const size_t a = static_cast<size_t>(entry.index);
      // Padded, so that a point whose float distance rounds to within the
      // radius is never in a cell beyond the box.
      const double reach =
          radius[a] * (1 + 1e-5) + 1e-6 * (std::abs(q[0]) + std::abs(q[1]) + std::abs(q[2]) + 1);
      grid->Nearest(q, static_cast<int32_t>(a), static_cast<float>(radius[a] * radius[a]), reach, k,
                    &out[(order ? e : a) * k], &best);
    }
  }
  if (order) {
    // The neighbours as rows, once the grid is gone: its entries are five
    // times the size of the map.
    grid.reset();
    std::vector<int32_t> row(n);
    for (size_t e = 0; e < n; ++e) row[(*order)[e]] = static_cast<int32_t>(e);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < out.size(); ++i) {
      if (out[i] >= 0) out[i] = row[out[i]];
    }
  }
  return out;
}

std::vector<int32_t> NearestOther(const std::vector<float>& xyz,
                                  const std::vector<size_t>& queries) {
  if (xyz.size() % 3 != 0) {
    throw Error("NearestOther: expected 3 coordinates per point (" + std::to_string(xyz.size()) +
                " coordinates)");
  }
  const size_t n = xyz.size() / 3;
  if (n > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    throw Error("NearestOther: " + std::to_string(n) +
                " points, more than an int32 index holds (2^31 - 1)");
  }
  for (const size_t q : queries) {
    if (q >= n) {
      throw Error("NearestOther: query " + std::to_string(q) + " of " + std::to_string(n) +
                  " points");
    }
  }
  std::vector<int32_t> out(queries.size(), -1);
  if (n < 2) return out;
  // The cloud's extent over its two widest axes, and its diagonal: the
  // reach past which no point can lie.
  const auto bounds = Bounds(xyz);
  const std::array<double, 3>& lo = bounds.first;
  const std::array<double, 3>& hi = bounds.second;
  std::array<double, 3> extent = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  std::sort(extent.begin(), extent.end(), std::greater<double>());
  const double diagonal =
      std::sqrt(extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]);
  // About four points per column where the points are spread evenly; a
  // cloud on a line or at one point falls back to the grid's own floor.
  const double spacing = std::sqrt(extent[0] * extent[1] / static_cast<double>(n));
  const ColumnGrid grid(xyz, spacing > 0 ? 2 * spacing : diagonal / 1024);
  const double first_reach = spacing > 0 ? 2 * spacing : std::max(diagonal, 1e-30);
  const long m = static_cast<long>(queries.size());
#pragma omp parallel
  {
    std::vector<uint64_t> best;
#pragma omp for schedule(dynamic, 512)
    for (long i = 0; i < m; ++i) {
      const size_t a = queries[i];
      const float* p = &xyz[3 * a];
      const double pad = 1e-6 * (std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]) + 1);
      for (double reach = first_reach;; reach *= 2) {
        const float r2 = static_cast<float>(reach * reach);
        grid.Nearest(p, static_cast<int32_t>(a), r2, reach * (1 + 1e-5) + pad, 1, &out[i], &best);
        // Past the diagonal every other point was within reach.
        if (out[i] >= 0 || reach > 2 * diagonal + pad) break;
      }
    }
  }
  return out;
}

}  // namespace sapmvs

#include "sapmvs/run/cloud_merge.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <tuple>
#include <unordered_map>

#include "sapmvs/run/core_index.h"
#include "sapmvs/util/error.h"

namespace sapmvs {

std::string MergeOptions::Problem() const {
  if (!(std::isfinite(radius) && radius > 0)) {
    std::ostringstream s;
    s << "a merge radius finite and > 0 (radius = " << radius << ")";
    return s.str();
  }
  if (!(std::isfinite(outside_core_radii) && outside_core_radii >= 1)) {
    std::ostringstream s;
    s << "an outside-core radius >= 1 radius (outside_core_radii = " << outside_core_radii << ")";
    return s.str();
  }
  if (!(std::isfinite(seam_feather_radii) && seam_feather_radii >= 0) ||
      !(std::isfinite(seam_band_radii) && seam_band_radii > 0)) {
    std::ostringstream s;
    s << "a seam feather >= 0 and a seam band > 0 (seam_feather_radii = " << seam_feather_radii
      << ", seam_band_radii = " << seam_band_radii << ")";
    return s.str();
  }
  if (!(std::isfinite(blend_radii) && blend_radii >= 0)) {
    std::ostringstream s;
    s << "a blend band >= 0 radii (blend_radii = " << blend_radii << ")";
    return s.str();
  }
  if (!(std::isfinite(surface_depth_radii) && surface_depth_radii >= 0)) {
    std::ostringstream s;
    s << "a surface depth >= 0 radii (surface_depth_radii = " << surface_depth_radii << ")";
    return s.str();
  }
  if (!(std::isfinite(vote_zone_radii) && vote_zone_radii >= 0 &&
        std::isfinite(vote_column_radii) && vote_column_radii > 0 &&
        std::isfinite(vote_reach_depths) && vote_reach_depths >= 1)) {
    std::ostringstream s;
    s << "a vote zone >= 0, a vote column > 0 radii and a vote reach >= 1 depth "
         "(vote_zone_radii = "
      << vote_zone_radii << ", vote_column_radii = " << vote_column_radii
      << ", vote_reach_depths = " << vote_reach_depths << ")";
    return s.str();
  }
  if (tile_points < 1000)
    return "merge tile points >= 1000 (tile_points = " + std::to_string(tile_points) + ")";
  if (!(std::isfinite(halo_radii) && halo_radii >= 1)) {
    std::ostringstream s;
    s << "a merge halo >= 1 radius (halo_radii = " << halo_radii << ")";
    return s.str();
  }
  return "";
}

double BeyondBisector(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      const Eigen::Vector2d& p) {
  const double length = (b - a).norm();
  if (!(length > 0)) return std::numeric_limits<double>::infinity();
  return ((p - b).squaredNorm() - (p - a).squaredNorm()) / (2 * length);
}

namespace {

struct CellKey {
  int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    // Unsigned: the products wrap, where signed ones overflowed (undefined)
    // for cells of UTM-sized coordinates (UBSan, CloudMerge tests).
    return static_cast<size_t>(static_cast<uint64_t>(k.x) * 73856093ULL ^
                               static_cast<uint64_t>(k.y) * 19349663ULL ^
                               static_cast<uint64_t>(k.z) * 83492791ULL);
  }
};

// Points hashed into cubes of side twice `radius`: everything within the
// radius of a point lies in the cubes its box of half-side radius overlaps,
// two along each axis in most cases, 8 lookups where cubes of side radius
// took 27 (the merge's greedy pass spent most of its time in them).
template <typename Ref>
class RadiusGrid {
 public:
  explicit RadiusGrid(double radius) : r_(radius), side_(2 * radius) {}
  void Insert(const Eigen::Vector3d& p, const Ref& ref) { cells_[Key(p)].push_back(ref); }
  // True as soon as `hit(ref)` holds for an inserted ref in a cube that may
  // hold points within the radius of p.
  template <typename Hit>
  bool AnyNear(const Eigen::Vector3d& p, const Hit& hit) const {
    // Padded, so that rounding in p +- radius never leaves out a cube with
    // a point whose distance to p a caller computes as within the radius;
    // and never more than the cube beside p's along an axis, which such a
    // point cannot pass (a radius near the coordinates' rounding, as a
    // test's 1e-9 at UTM coordinates, would otherwise span millions).
    const double reach = r_ * (1 + 1e-9) + 1e-9 * (p.cwiseAbs().maxCoeff() + 1);
    const CellKey at = Key(p);
    const CellKey lo = Key(p - Eigen::Vector3d::Constant(reach));
    const CellKey hi = Key(p + Eigen::Vector3d::Constant(reach));
    for (int64_t x = std::max(lo.x, at.x - 1); x <= std::min(hi.x, at.x + 1); ++x) {
      for (int64_t y = std::max(lo.y, at.y - 1); y <= std::min(hi.y, at.y + 1); ++y) {
        for (int64_t z = std::max(lo.z, at.z - 1); z <= std::min(hi.z, at.z + 1); ++z) {
          const auto it = cells_.find(CellKey{x, y, z});
          if (it == cells_.end()) continue;
          for (const Ref& ref : it->second) {
            if (hit(ref)) return true;
          }
        }
      }
    }
    return false;
  }
  // Calls `visit(ref)` for every inserted ref in those cubes.
  template <typename Visit>
  void ForEachNear(const Eigen::Vector3d& p, const Visit& visit) const {
    AnyNear(p, [&](const Ref& ref) {
      visit(ref);
      return false;
    });
  }

 private:
  CellKey Key(const Eigen::Vector3d& p) const {
    return CellKey{static_cast<int64_t>(std::floor(p.x() / side_)),
                   static_cast<int64_t>(std::floor(p.y() / side_)),
                   static_cast<int64_t>(std::floor(p.z() / side_))};
  }
  double r_;
  double side_;
  std::unordered_map<CellKey, std::vector<Ref>, CellHash> cells_;
};

struct Ref {
  int group;
  size_t index;
};

// Side of the coarse columns, in merge radii.
constexpr double kCoarseCell = 8.0;

// For each point of each group (in group order, then point order): whether a
// point of another group may lie within `radius` of it. Coarse columns of
// side kCoarseCell radii record which groups have points in them; a point
// none of whose columns within the radius holds another group's points has
// no duplicate and is nobody's, so the greedy pass keeps it without a lookup
// in its fine grid, and the result is the same. Conservative: "may" is by
// column. The fine grid's 27 hash lookups per point were most of the merge's
// time: `small`'s merge stage took 0.82-0.88 s with them for every point,
// 0.35-0.44 s with them for the contested ones.
std::vector<uint8_t> MayHaveForeignNeighbour(const std::vector<GroupCloud>& groups, double radius) {
  struct Column {
    int group = -1;  // the first group seen in it
    bool mixed = false;
  };
  const double side = kCoarseCell * radius;
  auto key = [&](double x, double y) {
    return CellKey{static_cast<int64_t>(std::floor(x / side)),
                   static_cast<int64_t>(std::floor(y / side)), 0};
  };
  std::unordered_map<CellKey, Column, CellHash> columns;
  size_t total = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const CloudPoint& p : groups[g].cloud->points) {
      Column& c = columns[key(p.position.x(), p.position.y())];
      if (c.group < 0) c.group = static_cast<int>(g);
      if (c.group != static_cast<int>(g)) c.mixed = true;
    }
    total += groups[g].cloud->points.size();
  }
  std::vector<uint8_t> may(total, 0);
  size_t first = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto& pts = groups[g].cloud->points;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < pts.size(); ++i) {
      const Eigen::Vector3d& p = pts[i].position;
      const CellKey lo = key(p.x() - radius, p.y() - radius);
      const CellKey hi = key(p.x() + radius, p.y() + radius);
      bool foreign = false;
      for (int64_t x = lo.x; x <= hi.x && !foreign; ++x) {
        for (int64_t y = lo.y; y <= hi.y && !foreign; ++y) {
          const auto it = columns.find(CellKey{x, y, 0});
          foreign =
              it != columns.end() && (it->second.mixed || it->second.group != static_cast<int>(g));
        }
      }
      may[first + i] = foreign;
    }
    first += pts.size();
  }
  return may;
}

// Whether a unit or zero normal (unknown) faces up or down enough for its
// point to lie on a surface a vertical column cuts (MergeOptions::vote_*).
bool FacesUpOrDown(const Eigen::Vector3f& n) {
  return n.squaredNorm() < 0.5f || std::abs(n.z()) >= 0.5f;
}

// A kept point near a border, for the column vote: where it sits in the
// merge's order, how far it lies from its core's border, and whether it
// votes (FacesUpOrDown). 40 bytes: a tile's near points are held at once,
// and on Caliterra they set the run's peak.
struct Voter {
  Eigen::Vector3d position;
  uint32_t slot;
  float border;
  bool up;
};

// MergeOptions::vote_zone_radii: marks in `drop` (by slot) the points within
// `zone` of a border whose column's median height lies more than `deep`
// from theirs. Sorts `voters` by column.
void VoteNearBorders(std::vector<Voter>* voters, double zone, double column, double deep,
                     double reach, std::vector<uint8_t>* drop) {
  auto key = [&](const Eigen::Vector3d& p) {
    return CellKey{static_cast<int64_t>(std::floor(p.x() / column)),
                   static_cast<int64_t>(std::floor(p.y() / column)), 0};
  };
  // Each column's points a contiguous range: through the groups' clouds,
  // every voter was a cache miss.
  std::sort(voters->begin(), voters->end(), [&](const Voter& a, const Voter& b) {
    const CellKey ka = key(a.position), kb = key(b.position);
    return std::tie(ka.x, ka.y, a.slot) < std::tie(kb.x, kb.y, b.slot);
  });
  const std::vector<Voter>& v = *voters;
  struct Column {
    uint32_t begin, end;
    double low, high;  // of its points' heights
  };
  std::unordered_map<CellKey, Column, CellHash> columns;
  for (size_t k = 0; k < v.size();) {
    const CellKey at = key(v[k].position);
    Column c{static_cast<uint32_t>(k), static_cast<uint32_t>(k), v[k].position.z(),
             v[k].position.z()};
    for (; k < v.size() && key(v[k].position) == at; ++k) {
      c.low = std::min(c.low, v[k].position.z());
      c.high = std::max(c.high, v[k].position.z());
    }
    c.end = static_cast<uint32_t>(k);
    columns.emplace(at, c);
  }
  // Where the 3 x 3 columns around one hold heights within `deep` of each
  // other, no median can lie further from any of them: most of the ground,
  // skipped without a look at each pair.
  std::vector<uint32_t> judged;
  for (const auto& [at, c] : columns) {
    double low = c.low, high = c.high;
    for (int64_t x = at.x - 1; x <= at.x + 1; ++x) {
      for (int64_t y = at.y - 1; y <= at.y + 1; ++y) {
        const auto it = columns.find(CellKey{x, y, 0});
        if (it == columns.end()) continue;
        low = std::min(low, it->second.low);
        high = std::max(high, it->second.high);
      }
    }
    if (high - low <= deep) continue;
    for (uint32_t k = c.begin; k < c.end; ++k) {
      if (v[k].border < zone) judged.push_back(k);
    }
  }
  std::sort(judged.begin(), judged.end());
  const double column2 = column * column;
#pragma omp parallel
  {
    std::vector<double> dz;
#pragma omp for schedule(dynamic, 256)
    for (size_t i = 0; i < judged.size(); ++i) {
      const Voter& judge = v[judged[i]];
      const Eigen::Vector3d& p = judge.position;
      dz.clear();
      size_t steep = 0;
      const CellKey at = key(p);
      for (int64_t x = at.x - 1; x <= at.x + 1; ++x) {
        for (int64_t y = at.y - 1; y <= at.y + 1; ++y) {
          const auto it = columns.find(CellKey{x, y, 0});
          if (it == columns.end()) continue;
          for (uint32_t j = it->second.begin; j < it->second.end; ++j) {
            const Eigen::Vector3d d = v[j].position - p;
            if (d.x() * d.x() + d.y() * d.y() > column2 || std::abs(d.z()) > reach) continue;
            if (v[j].up) {
              dz.push_back(d.z());
            } else {
              ++steep;
            }
          }
        }
      }
      // Only the surfaces a vertical column cuts vote: a wall's points above
      // the ground at its foot would outvote it. A steep point is judged only
      // among them (a wrong match on open ground), not on a wall or a facade.
      if (dz.empty() || (!judge.up && steep * 3 > dz.size())) continue;
      const auto mid = dz.begin() + static_cast<long>(dz.size() / 2);
      std::nth_element(dz.begin(), mid, dz.end());
      (*drop)[judge.slot] = std::abs(*mid) > deep;
    }
  }
}

}  // namespace

std::vector<MergedRef> MergeGroupRefs(const std::vector<GroupCloud>& groups,
                                      const MergeOptions& options, MergeStats* stats,
                                      const CoreIndex* cores,
                                      std::vector<MergedRef>* band_outliers) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("merge: expected " + problem);
  MergeStats local;
  MergeStats& st = stats ? *stats : local;
  st = MergeStats{};
  st.kept_by_group.assign(groups.size(), 0);
  st.core_by_group.assign(groups.size(), 0);
  std::vector<MergedRef> order;
  if (groups.empty()) return order;
  for (const GroupCloud& g : groups) {
    if (!g.cloud) throw Error("merge: a group has no cloud");
  }
  if (groups.size() == 1) {
    // One group has no duplicates across groups and owns its whole core:
    // every point stays, in order (what the loop below gives, without its
    // sort and grid: 0.4 s of a 10 s run on `small` as one group).
    const long n = static_cast<long>(groups.front().cloud->points.size());
    order.reserve(static_cast<size_t>(n));
    for (long i = 0; i < n; ++i) order.push_back({0, static_cast<size_t>(i), true});
    st.input = st.kept = n;
    st.kept_by_group[0] = st.core_by_group[0] = n;
    return order;
  }

  std::vector<Eigen::Vector2d> centers;
  for (const GroupCloud& g : groups) centers.push_back(g.center);
  struct Item {
    Ref ref;
    bool core;
    bool contested;  // MayHaveForeignNeighbour
    bool blend;      // within options.blend_radii of its core's border
    float score;
    float border;  // distance to its core's border (0 with no blend band or vote)
  };
  const double wide = options.radius * options.outside_core_radii;
  const double blend_width = options.radius * options.blend_radii;
  const double border_reach = options.BorderReach();
  std::optional<CoreIndex> own_cores;
  if (!cores) cores = &own_cores.emplace(centers, border_reach);
  // A point outside its core is judged within `wide` of its normal line and
  // `deep` along it: the corners of that cylinder are `reach` away.
  const double deep = options.radius * options.surface_depth_radii;
  const double reach = std::max(wide, std::hypot(wide, deep));
  const std::vector<uint8_t> contested = MayHaveForeignNeighbour(groups, wide);
  const std::vector<uint8_t> contested_far =
      reach > wide ? MayHaveForeignNeighbour(groups, reach) : contested;
  std::vector<Item> items(contested.size());
  size_t flat = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto& pts = groups[g].cloud->points;
    st.input += static_cast<long>(pts.size());
    // The core owner compares each point with every group's centre.
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < pts.size(); ++i) {
      // The distance to the border only where the blend band or the vote
      // asks for it.
      const double x = pts[i].position.x(), y = pts[i].position.y();
      const auto [owner, border] =
          border_reach > 0 ? cores->OwnerAndBorder({x, y}) : std::pair{cores->Owner({x, y}), 0.0};
      const bool core = owner == static_cast<int>(g);
      items[flat + i] = {
          {static_cast<int>(g), i}, core,         (core ? contested : contested_far)[flat + i] != 0,
          border < blend_width,     pts[i].score, static_cast<float>(border)};
    }
    flat += pts.size();
  }
  // Core points first so that the owner's surface wins; then the better match.
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    if (a.core != b.core) return a.core;
    return a.score > b.score;
  });

  auto point = [&](const Ref& ref) -> const CloudPoint& {
    return groups[ref.group].cloud->points[ref.index];
  };
  // Core points are looked up within the radius, the others within `wide`,
  // each in a grid of its own reach (RadiusGrid looks one cube around).
  RadiusGrid<Ref> kept(options.radius), kept_wide(reach);
  // Kept points near a border, for the column vote.
  const double vote_zone = options.radius * options.vote_zone_radii;
  const double vote_column = options.radius * options.vote_column_radii;
  std::vector<Voter> near;
  for (const Item& item : items) {
    if (item.contested) {
      const Eigen::Vector3d& p = point(item.ref).position;
      const double r = item.core ? options.radius : wide;
      const double r2 = r * r;
      // Outside its core, the cylinder along the point's normal where it
      // has one (a zero normal: unknown), else the sphere.
      const Eigen::Vector3d n = point(item.ref).normal.cast<double>();
      const bool cylinder = !item.core && reach > wide && n.squaredNorm() > 0.5;
      const bool duplicate =
          !item.blend && (item.core ? kept : kept_wide).AnyNear(p, [&](const Ref& other) {
            if (other.group == item.ref.group) return false;
            const Eigen::Vector3d d = point(other).position - p;
            if (!cylinder) return d.squaredNorm() <= r2;
            const double along = d.dot(n);
            return std::abs(along) <= deep && d.squaredNorm() - along * along <= r2;
          });
      if (duplicate) {
        ++st.duplicates;
        continue;
      }
      kept.Insert(p, item.ref);
      kept_wide.Insert(p, item.ref);
    }
    if (vote_zone > 0 && item.border < vote_zone + vote_column) {
      const CloudPoint& p = point(item.ref);
      near.push_back(
          {p.position, static_cast<uint32_t>(order.size()), item.border, FacesUpOrDown(p.normal)});
    }
    order.push_back({item.ref.group, item.ref.index, item.core});
  }
  if (!near.empty()) {
    std::vector<uint8_t> drop(order.size(), 0);
    VoteNearBorders(&near, vote_zone, vote_column, deep, options.vote_reach_depths * deep, &drop);
    near = std::vector<Voter>();
    std::vector<MergedRef> dropped;
    size_t to = 0;
    for (size_t i = 0; i < order.size(); ++i) {
      if (drop[i]) {
        dropped.push_back(order[i]);
      } else {
        order[to++] = order[i];
      }
    }
    order.resize(to);
    st.band_outliers = static_cast<long>(dropped.size());
    if (band_outliers) *band_outliers = std::move(dropped);
  }
  for (const MergedRef& ref : order) {
    ++st.kept_by_group[ref.group];
    if (ref.core) ++st.core_by_group[ref.group];
  }
  // Output in group order, each group's points in their original order, so
  // that the merged file does not depend on score ties.
  std::sort(order.begin(), order.end(), [](const MergedRef& a, const MergedRef& b) {
    return a.group != b.group ? a.group < b.group : a.index < b.index;
  });
  st.kept = static_cast<long>(order.size());
  return order;
}

PointCloud MergeGroupClouds(const std::vector<GroupCloud>& groups, const MergeOptions& options,
                            MergeStats* stats) {
  const std::vector<MergedRef> order = MergeGroupRefs(groups, options, stats);
  PointCloud out;
  if (groups.empty()) return out;
  const PointCloud& first = *groups.front().cloud;
  out.crs = first.crs;
  out.has_normals = first.has_normals;
  out.has_colors = first.has_colors;
  out.has_scores = first.has_scores;
  out.has_views = first.has_views;
  out.points.reserve(order.size());
  for (const MergedRef& ref : order)
    out.points.push_back(groups[ref.group].cloud->points[ref.index]);
  return out;
}

long CountCrossGroupPairs(const PointCloud& cloud, const std::vector<int>& group_of,
                          double radius) {
  if (!(std::isfinite(radius) && radius > 0)) {
    throw Error("cross-group pairs: expected a radius > 0");
  }
  if (group_of.size() != cloud.points.size()) {
    throw Error("cross-group pairs: expected one group per point (" +
                std::to_string(group_of.size()) + " for " + std::to_string(cloud.points.size()) +
                " points)");
  }
  RadiusGrid<size_t> grid(radius);
  for (size_t i = 0; i < cloud.points.size(); ++i) grid.Insert(cloud.points[i].position, i);
  long pairs = 0;
  for (size_t i = 0; i < cloud.points.size(); ++i) {
    const Eigen::Vector3d& p = cloud.points[i].position;
    grid.ForEachNear(p, [&](size_t j) {
      pairs +=
          j > i && group_of[j] != group_of[i] && (cloud.points[j].position - p).norm() <= radius;
    });
  }
  return pairs;
}

namespace {

// How many points of `from` have a point j of `to` within `radius` for which
// hit(point, j) holds; `has`, if given, receives the answer per point.
template <typename Hit>
long CountWithNear(const PointCloud& from, const PointCloud& to, double radius, const Hit& hit,
                   std::vector<bool>* has = nullptr) {
  RadiusGrid<size_t> grid(radius);
  for (size_t i = 0; i < to.points.size(); ++i) grid.Insert(to.points[i].position, i);
  long with = 0;
  if (has) has->assign(from.points.size(), false);
  for (size_t i = 0; i < from.points.size(); ++i) {
    const CloudPoint& p = from.points[i];
    const bool near = grid.AnyNear(p.position, [&](size_t j) { return hit(p, j); });
    with += near;
    if (has) (*has)[i] = near;
  }
  return with;
}

}  // namespace

long CountWithNeighbour(const PointCloud& from, const PointCloud& to, double radius,
                        std::vector<bool>* has) {
  if (!(std::isfinite(radius) && radius > 0)) {
    throw Error("neighbour count: expected a radius > 0");
  }
  return CountWithNear(
      from, to, radius,
      [&](const CloudPoint& p, size_t j) {
        return (to.points[j].position - p.position).norm() <= radius;
      },
      has);
}

long CountNearSurface(const PointCloud& from, const PointCloud& to, double tolerance,
                      double reach) {
  if (!(std::isfinite(tolerance) && tolerance > 0 && std::isfinite(reach) && reach >= tolerance)) {
    throw Error("surface count: expected 0 < tolerance <= reach");
  }
  if (!to.points.empty() && !to.has_normals) {
    throw Error("surface count: the compared cloud has no normals");
  }
  // Unit normals once, not per pair; a sample without a normal gives no plane.
  std::vector<Eigen::Vector3d> normals(to.points.size(), Eigen::Vector3d::Zero());
  for (size_t j = 0; j < to.points.size(); ++j) {
    const Eigen::Vector3d n = to.points[j].normal.cast<double>();
    if (n.squaredNorm() > 0) normals[j] = n.normalized();
  }
  return CountWithNear(from, to, reach, [&](const CloudPoint& p, size_t j) {
    const Eigen::Vector3d d = p.position - to.points[j].position;
    return !normals[j].isZero() && d.norm() <= reach && std::abs(normals[j].dot(d)) <= tolerance;
  });
}

}  // namespace sapmvs

#include "sapmvs/cloud_merge.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "sapmvs/error.h"

namespace sapmvs {

std::string MergeOptions::Problem() const {
  if (!(std::isfinite(radius) && radius > 0)) {
    std::ostringstream s;
    s << "a merge radius finite and > 0 (radius = " << radius << ")";
    return s.str();
  }
  return "";
}

int CoreOwner(const std::vector<GroupCloud>& groups, double x, double y) {
  int best = -1;
  double best_d2 = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const double dx = x - groups[g].center.x(), dy = y - groups[g].center.y();
    const double d2 = dx * dx + dy * dy;
    if (best < 0 || d2 < best_d2) {
      best = static_cast<int>(g);
      best_d2 = d2;
    }
  }
  return best;
}

namespace {

struct CellKey {
  int64_t x, y, z;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    return static_cast<size_t>(k.x * 73856093LL ^ k.y * 19349663LL ^ k.z * 83492791LL);
  }
};

struct Ref {
  int group;
  size_t index;
};

}  // namespace

PointCloud MergeGroupClouds(const std::vector<GroupCloud>& groups, const MergeOptions& options,
                            MergeStats* stats) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("merge: expected " + problem);
  MergeStats local;
  MergeStats& st = stats ? *stats : local;
  st = MergeStats{};
  st.kept_by_group.assign(groups.size(), 0);
  st.core_by_group.assign(groups.size(), 0);
  PointCloud out;
  if (groups.empty()) return out;
  for (const GroupCloud& g : groups) {
    if (!g.cloud) throw Error("merge: a group has no cloud");
  }
  const PointCloud& first = *groups.front().cloud;
  out.crs = first.crs;
  out.has_normals = first.has_normals;
  out.has_colors = first.has_colors;
  out.has_scores = first.has_scores;
  out.has_views = first.has_views;

  struct Item {
    Ref ref;
    bool core;
    float score;
  };
  std::vector<Item> items;
  for (size_t g = 0; g < groups.size(); ++g) {
    const auto& pts = groups[g].cloud->points;
    st.input += static_cast<long>(pts.size());
    for (size_t i = 0; i < pts.size(); ++i) {
      const bool core =
          CoreOwner(groups, pts[i].position.x(), pts[i].position.y()) == static_cast<int>(g);
      items.push_back({{static_cast<int>(g), i}, core, pts[i].score});
    }
  }
  // Core points first so that the owner's surface wins; then the better match.
  std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    if (a.core != b.core) return a.core;
    return a.score > b.score;
  });

  const double r = options.radius;
  const double r2 = r * r;
  auto point = [&](const Ref& ref) -> const CloudPoint& {
    return groups[ref.group].cloud->points[ref.index];
  };
  auto key = [&](const Eigen::Vector3d& p) {
    return CellKey{static_cast<int64_t>(std::floor(p.x() / r)),
                   static_cast<int64_t>(std::floor(p.y() / r)),
                   static_cast<int64_t>(std::floor(p.z() / r))};
  };
  std::unordered_map<CellKey, std::vector<Ref>, CellHash> kept;
  std::vector<Ref> order;
  for (const Item& item : items) {
    const Eigen::Vector3d& p = point(item.ref).position;
    const CellKey k = key(p);
    bool duplicate = false;
    for (int dx = -1; dx <= 1 && !duplicate; ++dx) {
      for (int dy = -1; dy <= 1 && !duplicate; ++dy) {
        for (int dz = -1; dz <= 1 && !duplicate; ++dz) {
          const auto it = kept.find(CellKey{k.x + dx, k.y + dy, k.z + dz});
          if (it == kept.end()) continue;
          for (const Ref& other : it->second) {
            if (other.group != item.ref.group && (point(other).position - p).squaredNorm() <= r2) {
              duplicate = true;
              break;
            }
          }
        }
      }
    }
    if (duplicate) {
      ++st.duplicates;
      continue;
    }
    kept[k].push_back(item.ref);
    order.push_back(item.ref);
    ++st.kept_by_group[item.ref.group];
    if (item.core) ++st.core_by_group[item.ref.group];
  }
  // Output in group order, each group's points in their original order, so
  // that the merged file does not depend on score ties.
  std::sort(order.begin(), order.end(), [](const Ref& a, const Ref& b) {
    return a.group != b.group ? a.group < b.group : a.index < b.index;
  });
  out.points.reserve(order.size());
  for (const Ref& ref : order) out.points.push_back(point(ref));
  st.kept = static_cast<long>(out.points.size());
  return out;
}

}  // namespace sapmvs

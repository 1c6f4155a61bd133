// The images' ground footprints and what the planner measures with them.
#include <algorithm>

#include "plan/grouping_internal.h"
#include "sapmvs/block/block_geometry.h"

namespace sapmvs {

namespace {

// Share of footprint f's 7 x 7 samples (SelectViews counts views so) for
// which `inside` holds.
template <typename Inside>
double SampledShare(const Footprint& f, const Inside& inside) {
  constexpr int kGrid = 7;
  int count = 0;
  for (int gy = 0; gy < kGrid; ++gy) {
    for (int gx = 0; gx < kGrid; ++gx) {
      const double u = (gx + 0.5) / kGrid, v = (gy + 0.5) / kGrid;
      const auto& c = f.corners;
      count += inside(
          Eigen::Vector2d((1 - v) * ((1 - u) * c[0] + u * c[1]) + v * ((1 - u) * c[3] + u * c[2])));
    }
  }
  return static_cast<double>(count) / (kGrid * kGrid);
}

}  // namespace

std::vector<Footprint> Footprints(const Block& block, const BlockGeometry& geometry) {
  std::vector<Footprint> out(block.images.size());
  for (size_t i = 0; i < out.size(); ++i) {
    Footprint& f = out[i];
    const ImageGeometry& g = geometry.images[i];
    f.center = (block.images[i].camera.center() - block.origin).head<2>();
    if (!g.valid) continue;
    f.valid = true;
    f.center.setZero();
    for (int k = 0; k < 4; ++k) {
      f.corners[k] = (g.footprint[k] - block.origin).head<2>();
      f.center += f.corners[k] / 4;
    }
    f.lo = f.hi = f.corners[0];
    for (const Eigen::Vector2d& c : f.corners) {
      f.lo = f.lo.cwiseMin(c);
      f.hi = f.hi.cwiseMax(c);
    }
    f.scene_z = g.scene_point.z() - block.origin.z();
    f.short_side =
        std::min((f.corners[1] - f.corners[0]).norm(), (f.corners[3] - f.corners[0]).norm());
  }
  return out;
}

GroupMemory EstimateInProcess(const Block& block, const std::vector<int>& ids,
                              const MatcherOptions& matcher, double process_bytes) {
  GroupMemory mem = EstimateGroupMemory(block, ids, matcher);
  mem.process_bytes = process_bytes;
  return mem;
}

std::vector<double> CellShares(const ImageGroup& g, const std::vector<Footprint>& fp) {
  const bool tiled = (g.tile_max.array() > g.tile_min.array()).all();
  std::vector<double> shares;
  for (const int i : g.images) {
    if (!tiled || !fp[i].valid) {
      shares.push_back(1.0);
      continue;
    }
    shares.push_back(SampledShare(fp[i], [&](const Eigen::Vector2d& p) {
      return (p.array() >= g.tile_min.array()).all() && (p.array() <= g.tile_max.array()).all();
    }));
  }
  shares.resize(shares.size() + g.views.size(), 0.0);
  return shares;
}

GroupMemory EstimateInProcess(const Block& block, const ImageGroup& g,
                              const std::vector<Footprint>& fp, const MatcherOptions& matcher,
                              double process_bytes) {
  GroupMemory mem = EstimateGroupMemory(block, g.MatchedIn(), matcher, CellShares(g, fp));
  mem.process_bytes = process_bytes;
  return mem;
}

bool Fits(const Block& block, const std::vector<int>& ids, const GroupingPlan& plan) {
  return EstimateInProcess(block, ids, plan.matcher, plan.process_bytes).Total() <=
         plan.options.memory_budget;
}

bool Fits(const Block& block, const ImageGroup& g, const std::vector<Footprint>& fp,
          const GroupingPlan& plan) {
  return EstimateInProcess(block, g, fp, plan.matcher, plan.process_bytes).Total() <=
         plan.options.memory_budget;
}

Eigen::Vector2d MeanCenter(const std::vector<Footprint>& fp, const std::vector<int>& ids) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const int i : ids) c += fp[i].center;
  return c / static_cast<double>(ids.size());
}

double OverlapShare(const std::vector<Footprint>& fp, int i, int j) {
  if (!fp[i].valid || !fp[j].valid) return 1.0;
  return SampledShare(fp[i], [&](const Eigen::Vector2d& p) { return fp[j].Contains(p); });
}

std::vector<int> ShortOfViews(const std::vector<Footprint>& fp, const std::vector<int>& ids,
                              int min_image_num, const std::vector<int>& matched_in) {
  std::vector<int> out;
  for (const int i : ids) {
    int views = 0;
    for (const int j : matched_in) views += j != i && OverlapShare(fp, i, j) >= 0.1;
    if (views < min_image_num - 1) out.push_back(i);
  }
  return out;
}

}  // namespace sapmvs

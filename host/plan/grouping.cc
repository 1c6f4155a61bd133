#include "sapmvs/plan/grouping.h"
#include "sapmvs/util/byte_size.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <sstream>
#include <tuple>

#include "plan/strip_detection.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {
namespace {

// Samples per tile side for the footprint strategy's coverage counts: 256
// points per tile, at 256 point-in-quad tests per image and tile. 8 x 8
// missed the slivers at the block's fringe that only 2 images of a strip
// see (attitude noise wobbles the footprints' sides), so the greedy cover
// left them with one view at the paper's 92 % forward overlap.
constexpr int kTileSamples = 16;

// Where each image sees the ground, local frame.
struct Footprint {
  bool valid = false;
  std::array<Eigen::Vector2d, 4> corners;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // of the corners; camera XY when invalid
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();  // bounding box
  double scene_z = 0;
  double short_side = 0;

  bool Contains(const Eigen::Vector2d& p) const {
    if (!valid || (p.array() < lo.array()).any() || (p.array() > hi.array()).any()) return false;
    // Convex quad: p is inside when it lies on one side of every edge.
    int pos = 0, neg = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d e = corners[(k + 1) % 4] - corners[k], q = p - corners[k];
      const double c = e.x() * q.y() - e.y() * q.x();
      pos += c > 0;
      neg += c < 0;
    }
    return pos == 0 || neg == 0;
  }
};

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

std::string GroupNames(const Block& block, const std::vector<int>& ids) {
  std::string s;
  for (size_t k = 0; k < ids.size() && k < 4; ++k) s += (k ? ", " : "") + block.images[ids[k]].name;
  return ids.size() > 4 ? s + ", ..." : s;
}

// A group's estimate with the process around it (PlanGroups' process_bytes),
// which is what memory_budget bounds.
GroupMemory EstimateInProcess(const Block& block, const std::vector<int>& ids,
                              const MatcherOptions& matcher, double process_bytes) {
  GroupMemory mem = EstimateGroupMemory(block, ids, matcher);
  mem.process_bytes = process_bytes;
  return mem;
}

// Throws when the smallest group that can be matched does not fit: the
// min_image_num (at least 2) largest images, as a point needs that many
// views. Every other group of that size then fits too, as the estimate grows
// with pixels; a budget that only fit smaller groups would match nothing.
void CheckSmallestGroupFits(const Block& block, const GroupingOptions& o, const MatcherOptions& m,
                            double process_bytes) {
  std::vector<int> ids(block.images.size());
  std::iota(ids.begin(), ids.end(), 0);
  const size_t k = std::min(ids.size(), static_cast<size_t>(std::max(2, m.min_image_num)));
  std::partial_sort(ids.begin(), ids.begin() + k, ids.end(), [&](int a, int b) {
    const Camera &ca = block.images[a].camera, &cb = block.images[b].camera;
    return static_cast<double>(ca.width()) * ca.height() >
           static_cast<double>(cb.width()) * cb.height();
  });
  ids.resize(k);
  const GroupMemory mem = EstimateInProcess(block, ids, m, process_bytes);
  if (mem.Total() > o.memory_budget) {
    throw Error(
        "memory budget " + FormatBytes(o.memory_budget) + " is too small: " + std::to_string(k) +
        " images, the fewest a group can match (min_image_num " + std::to_string(m.min_image_num) +
        "), need " + FormatBytes(mem.Total()) + " at level " + std::to_string(m.level) + " (" +
        GroupNames(block, ids) + ": device " + FormatBytes(mem.device_bytes) + " + host " +
        FormatBytes(mem.host_bytes) +
        (process_bytes > 0 ? " + the process before matching " + FormatBytes(process_bytes)
                           : std::string()) +
        "); raise the budget or match at a coarser level");
  }
}

// The plan's options and matcher say what a group may use.
bool Fits(const Block& block, const std::vector<int>& ids, const GroupingPlan& plan) {
  return EstimateInProcess(block, ids, plan.matcher, plan.process_bytes).Total() <=
         plan.options.memory_budget;
}

Eigen::Vector2d MeanCenter(const std::vector<Footprint>& fp, const std::vector<int>& ids) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const int i : ids) c += fp[i].center;
  return c / static_cast<double>(ids.size());
}

// Runs of at most k images; a single image left at the end takes one from
// the run before it (k >= 3) or shares its last image (k = 2).
std::vector<std::vector<int>> CutRuns(const std::vector<int>& strip, size_t k) {
  std::vector<std::vector<int>> runs;
  for (size_t i = 0; i < strip.size(); i += k)
    runs.emplace_back(strip.begin() + i, strip.begin() + std::min(i + k, strip.size()));
  if (runs.size() >= 2 && runs.back().size() == 1) {
    std::vector<int>& prev = runs[runs.size() - 2];
    runs.back().insert(runs.back().begin(), prev.back());
    if (prev.size() >= 3) prev.pop_back();
  }
  return runs;
}

// Share of image i's footprint that image j sees (7 x 7 samples, as
// SelectViews counts views); 1 when either has no footprint, since nothing
// then says they do not overlap.
double OverlapShare(const std::vector<Footprint>& fp, int i, int j) {
  if (!fp[i].valid || !fp[j].valid) return 1.0;
  constexpr int kGrid = 7;
  int inside = 0;
  for (int gy = 0; gy < kGrid; ++gy) {
    for (int gx = 0; gx < kGrid; ++gx) {
      const double u = (gx + 0.5) / kGrid, v = (gy + 0.5) / kGrid;
      const auto& c = fp[i].corners;
      const Eigen::Vector2d p =
          (1 - v) * ((1 - u) * c[0] + u * c[1]) + v * ((1 - u) * c[3] + u * c[2]);
      inside += fp[j].Contains(p);
    }
  }
  return static_cast<double>(inside) / (kGrid * kGrid);
}

// Images of `ids` that overlap fewer than min_image_num - 1 others of
// `matched_in` (ImageGroup::MatchedIn: ids and the group's views).
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

void PlanStrips(const Block& block, const GroupingOptions& o, const std::vector<Footprint>& fp,
                GroupingPlan* plan) {
  std::vector<int> singles;
  for (size_t s = 0; s < plan->strips.size(); ++s) {
    const std::vector<int>& strip = plan->strips[s];
    if (strip.size() < 2) {
      singles.push_back(strip[0]);
      continue;
    }
    // One run length per strip keeps the paper's pattern (6+6+4) while the
    // budget allows, and shortens every run of the strip when it does not.
    std::vector<std::vector<int>> runs;
    for (int k = o.max_images; k >= 2; --k) {
      runs = CutRuns(strip, static_cast<size_t>(k));
      if (std::all_of(runs.begin(), runs.end(),
                      [&](const std::vector<int>& r) { return Fits(block, r, *plan); }))
        break;
    }
    // A run of fewer images than a patch needs matches nothing (a strip of
    // 14 cut 6+6+2): it takes the strip images before it, which the run
    // before it matched too; the merge keeps one of the duplicates.
    for (size_t r = 1; r < runs.size(); ++r) {
      std::vector<int>& run = runs[r];
      auto first = std::find(strip.begin(), strip.end(), run.front());
      while (static_cast<int>(run.size()) < std::min(plan->matcher.min_image_num, o.max_images) &&
             first != strip.begin()) {
        std::vector<int> with = run;
        with.insert(with.begin(), *(first - 1));
        if (!Fits(block, with, *plan)) break;
        run = std::move(with);
        --first;
      }
    }
    for (std::vector<int>& run : runs) {
      ImageGroup g;
      g.images = std::move(run);
      g.strip = static_cast<int>(s);
      plan->groups.push_back(std::move(g));
    }
  }
  if (plan->groups.empty()) {
    // No strip structure (a terrestrial or convergent block): its images in
    // block order are the one strip.
    std::vector<int> all(block.images.size());
    std::iota(all.begin(), all.end(), 0);
    GroupingPlan whole = *plan;
    whole.strips = {all};
    whole.groups.clear();
    PlanStrips(block, o, fp, &whole);
    plan->groups = std::move(whole.groups);
    for (ImageGroup& g : plan->groups) g.strip = -1;
    return;
  }
  for (ImageGroup& g : plan->groups) g.center = MeanCenter(fp, g.images);
  for (const int i : singles) {
    std::vector<size_t> order(plan->groups.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      return (plan->groups[a].center - fp[i].center).squaredNorm() <
             (plan->groups[b].center - fp[i].center).squaredNorm();
    });
    bool joined = false;
    for (const size_t gi : order) {
      ImageGroup& g = plan->groups[gi];
      std::vector<int> with = g.images;
      with.push_back(i);
      if (static_cast<int>(with.size()) > o.max_images || !Fits(block, with, *plan)) continue;
      g.images = std::move(with);
      g.center = MeanCenter(fp, g.images);
      joined = true;
      break;
    }
    if (!joined) plan->ungrouped.push_back(i);
  }
}

// Strip groups: up to strip_views images of other strips per group, as
// views only, those that see most of the group's footprints first (summed
// OverlapShare, each at least 10 % of one group image), while the group fits
// the budget. Views are re-ranked per image when matching (SelectViews), so
// more than kMaxViews - 1 here only helps where images see different ground.
void AddStripViews(const Block& block, const GroupingOptions& o, const std::vector<Footprint>& fp,
                   GroupingPlan* plan) {
  if (o.strip_views <= 0) return;
  std::vector<int> strip_of(block.images.size(), -1);
  for (size_t s = 0; s < plan->strips.size(); ++s)
    for (const int i : plan->strips[s]) strip_of[i] = static_cast<int>(s);
  for (ImageGroup& g : plan->groups) {
    if (g.strip < 0) continue;
    std::vector<std::pair<double, int>> ranked;
    for (size_t j = 0; j < block.images.size(); ++j) {
      if (!fp[j].valid || strip_of[j] == g.strip ||
          std::find(g.images.begin(), g.images.end(), static_cast<int>(j)) != g.images.end()) {
        continue;
      }
      double sum = 0, best = 0;
      for (const int i : g.images) {
        // Disjoint bounding boxes: no overlap, without the 7 x 7 samples.
        if (!fp[i].valid || (fp[i].hi.array() < fp[j].lo.array()).any() ||
            (fp[j].hi.array() < fp[i].lo.array()).any()) {
          continue;
        }
        const double share = OverlapShare(fp, i, static_cast<int>(j));
        sum += share;
        best = std::max(best, share);
      }
      if (best >= 0.1) ranked.emplace_back(sum, static_cast<int>(j));
    }
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    std::vector<int> with = g.images;
    for (const auto& [share, j] : ranked) {
      if (static_cast<int>(g.views.size()) >= o.strip_views) break;
      with.push_back(j);
      if (!Fits(block, with, *plan)) {
        with.pop_back();
        break;
      }
      g.views.push_back(j);
    }
  }
}

// Every tile costs kTileSamples^2 point-in-quad tests per image, so a tiny
// --tile-size (1e-6) would plan for hours. A tile narrower than
// kMinTilePixels image pixels holds too few patches to be worth a group, and
// the tile count is capped so that planning stays within seconds.
constexpr double kMinTilePixels = 64;
constexpr double kMaxTiles = 100000;

void CheckTileCost(const Block& block, const GroupingOptions& o, const std::vector<int>& valid,
                   const Eigen::Vector2d& tiles_xy) {
  std::vector<double> px;
  for (int i : valid) {
    const Camera& c = block.images[i].camera;
    px.push_back(std::min(c.width(), c.height()));
  }
  std::nth_element(px.begin(), px.begin() + px.size() / 2, px.end());
  const double short_px = px[px.size() / 2];
  const double tiles =
      std::max(1.0, std::ceil(tiles_xy.x())) * std::max(1.0, std::ceil(tiles_xy.y()));
  const double min_size =
      std::max(kMinTilePixels / short_px, o.tile_size * std::sqrt(tiles / kMaxTiles));
  if (o.tile_size * short_px < kMinTilePixels || tiles > kMaxTiles) {
    std::ostringstream s;
    s.precision(3);
    s << "--tile-size " << o.tile_size << " gives tiles of " << o.tile_size * short_px
      << " px (the median image's shorter side is " << short_px << " px) and " << tiles
      << " tiles; expected tiles of at least " << static_cast<int>(kMinTilePixels)
      << " px and at most " << static_cast<long>(kMaxTiles) << " tiles: --tile-size in ["
      << std::min(4.0, min_size) << ", 4]";
    throw Error(s.str());
  }
}

void PlanFootprint(const Block& block, const GroupingOptions& o, const BlockGeometry& geometry,
                   const std::vector<Footprint>& fp, GroupingPlan* plan) {
  if (!geometry.aerial) {
    throw Error("footprint grouping needs a block whose images look down; " +
                block.source.string() + " is not one (use the strip strategy)");
  }
  std::vector<int> valid;
  std::vector<double> sides;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < fp.size(); ++i) {
    if (!fp[i].valid || !geometry.images[i].looks_down) continue;
    valid.push_back(static_cast<int>(i));
    sides.push_back(fp[i].short_side);
    lo = lo.cwiseMin(fp[i].lo);
    hi = hi.cwiseMax(fp[i].hi);
  }
  if (valid.size() < 2) {
    throw Error("footprint grouping needs the ground footprints of at least 2 images, got " +
                std::to_string(valid.size()) + " (give the block a ground height or a DEM)");
  }
  std::nth_element(sides.begin(), sides.begin() + sides.size() / 2, sides.end());
  const double side = o.tile_size * sides[sides.size() / 2];
  const Eigen::Vector2d size = hi - lo;
  CheckTileCost(block, o, valid, size / side);
  const int nx = std::max(1, static_cast<int>(std::ceil(size.x() / side - 1e-9)));
  const int ny = std::max(1, static_cast<int>(std::ceil(size.y() / side - 1e-9)));
  // Tiles split the extent evenly, so the last ones are not slivers.
  const Eigen::Vector2d tile(size.x() / nx, size.y() / ny);
  std::vector<bool> used(block.images.size(), false);
  std::vector<int> tiles_in_group;  // per group of plan->groups
  for (int ty = 0; ty < ny; ++ty) {
    for (int tx = 0; tx < nx; ++tx) {
      const Eigen::Vector2d t0 = lo + Eigen::Vector2d(tx * tile.x(), ty * tile.y());
      const Eigen::Vector2d center = t0 + tile / 2;
      std::vector<Eigen::Vector2d> samples;
      for (int sy = 0; sy < kTileSamples; ++sy)
        for (int sx = 0; sx < kTileSamples; ++sx)
          samples.push_back(t0 + Eigen::Vector2d((sx + 0.5) * tile.x() / kTileSamples,
                                                 (sy + 0.5) * tile.y() / kTileSamples));
      struct Candidate {
        int image;
        std::vector<int> seen;  // sample indices
        double nadir;           // cosine of the ray from the tile centre to the camera
      };
      std::vector<Candidate> candidates;
      std::vector<int> views(samples.size(), 0);
      for (const int i : valid) {
        Candidate c{i, {}, 0};
        for (size_t s = 0; s < samples.size(); ++s)
          if (fp[i].Contains(samples[s])) c.seen.push_back(static_cast<int>(s));
        if (c.seen.empty()) continue;
        for (const int s : c.seen) ++views[s];
        const Eigen::Vector3d x(center.x(), center.y(), fp[i].scene_z);
        c.nadir = (block.images[i].camera.center() - block.origin - x).normalized().z();
        candidates.push_back(std::move(c));
      }
      if (*std::max_element(views.begin(), views.end()) < 2) continue;  // nothing to match
      // Greedy cover: next, the image that gives most samples their second
      // view (a sample at the block's fringe, seen by 2 images only, is
      // matchable only if the group holds both: at the paper's 92 % forward
      // overlap the central images alone fill the group otherwise), then
      // brings most samples closer to tile_views views; ties go to the
      // image that sees more of the tile, then to the more nadir one.
      ImageGroup g;
      const int target = std::min(o.tile_views, o.max_images);
      const std::vector<int> available = views;
      std::fill(views.begin(), views.end(), 0);
      std::vector<bool> taken(candidates.size(), false);
      while (static_cast<int>(g.images.size()) < o.max_images) {
        int best = -1;
        std::tuple<int, int, size_t, double> best_key{0, 0, 0, 0};
        for (size_t c = 0; c < candidates.size(); ++c) {
          if (taken[c]) continue;
          int gain = 0, second = 0;
          for (const int s : candidates[c].seen) {
            gain += views[s] < target;
            second += views[s] < std::min(2, available[s]);
          }
          const std::tuple<int, int, size_t, double> key{second, gain, candidates[c].seen.size(),
                                                         candidates[c].nadir};
          if (gain > 0 && (best < 0 || key > best_key)) {
            std::vector<int> with = g.images;
            with.push_back(candidates[c].image);
            if (!Fits(block, with, *plan)) continue;
            best = static_cast<int>(c);
            best_key = key;
          }
        }
        if (best < 0) break;
        taken[best] = true;
        g.images.push_back(candidates[best].image);
        for (const int s : candidates[best].seen) ++views[s];
      }
      if (g.images.size() < 2) continue;
      for (const int i : g.images) used[i] = true;
      // Neighbouring tiles often pick the same images; matching them twice
      // would only produce the same cloud twice, so they become one group
      // whose centre is the mean of its tiles' centres.
      std::vector<int> key_images = g.images;
      std::sort(key_images.begin(), key_images.end());
      bool merged = false;
      for (size_t k = 0; k < plan->groups.size() && !merged; ++k) {
        std::vector<int> other = plan->groups[k].images;
        std::sort(other.begin(), other.end());
        if (other != key_images) continue;
        ImageGroup& e = plan->groups[k];
        const double n = static_cast<double>(tiles_in_group[k]);
        e.center = (e.center * n + center) / (n + 1);
        e.tile_min = e.tile_min.cwiseMin(t0);
        e.tile_max = e.tile_max.cwiseMax(t0 + tile);
        ++tiles_in_group[k];
        merged = true;
      }
      if (merged) continue;
      g.center = center;
      g.tile_min = t0;
      g.tile_max = t0 + tile;
      plan->groups.push_back(std::move(g));
      tiles_in_group.push_back(1);
    }
  }
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i]) plan->ungrouped.push_back(static_cast<int>(i));
}

}  // namespace

std::string ToString(GroupingStrategy s) {
  return s == GroupingStrategy::kStrip ? "strip" : "footprint";
}

GroupingStrategy ParseGroupingStrategy(const std::string& text) {
  if (text == "strip") return GroupingStrategy::kStrip;
  if (text == "footprint") return GroupingStrategy::kFootprint;
  throw Error("unknown grouping strategy '" + text + "': expected strip or footprint");
}

std::string GroupingOptions::Problem() const { return FirstRangeProblem(*this); }

bool GroupingOptions::Check() const {
  const std::string problem = Problem();
  if (!problem.empty()) std::cerr << "GroupingOptions: expected " << problem << "\n";
  return problem.empty();
}

GroupMemory EstimateGroupMemory(const Block& block, const std::vector<int>& images, int level) {
  MatcherOptions matcher;
  matcher.level = level;
  return EstimateGroupMemory(block, images, matcher);
}

GroupMemory EstimateGroupMemory(const Block& block, const std::vector<int>& images,
                                const MatcherOptions& matcher) {
  if (matcher.level < 0 || matcher.level > kMaxLevel)
    throw Error("memory estimate: level in 0.." + std::to_string(kMaxLevel) + " expected, got " +
                std::to_string(matcher.level));
  const MatcherMemoryModel model = MatcherMemory();
  const double cs = std::max(1, matcher.cell_size);
  GroupMemory m;
  double load = 0;
  for (const int id : images) {
    if (id < 0 || id >= static_cast<int>(block.images.size()))
      throw Error("memory estimate: image index " + std::to_string(id) + " is outside the block");
    const Camera& cam = block.images[id].camera;
    const Intrinsics k = cam.intrinsics().Scaled(std::ldexp(1.0, -matcher.level));
    const double pixels = static_cast<double>(k.width) * k.height;
    const double cells = std::ceil(k.width / cs) * std::ceil(k.height / cs);
    m.device_bytes += model.device_bytes_per_pixel * pixels;
    m.host_bytes += model.host_bytes_per_pixel * pixels + model.host_bytes_per_cell * cells;
    load = std::max(load, 6.0 * cam.width() * cam.height());
  }
  const double wave = std::max(0, matcher.max_wave);
  m.device_bytes += wave * model.device_bytes_per_candidate;
  m.host_bytes += wave * model.host_bytes_per_candidate;
  m.host_bytes += load;
  return m;
}

GroupingPlan PlanGroups(const Block& block, const GroupingOptions& options,
                        const MatcherOptions& matcher, const BlockGeometry* known_geometry,
                        double process_bytes) {
  if (const std::string problem = options.Problem(); !problem.empty())
    throw Error("grouping options: expected " + problem);
  if (const std::string problem = matcher.Problem(); !problem.empty())
    throw Error("matcher options: expected " + problem);
  if (block.images.size() < 2) {
    throw Error("grouping needs at least 2 images, " + block.source.string() + " has " +
                std::to_string(block.images.size()));
  }
  if (!(std::isfinite(process_bytes) && process_bytes >= 0))
    throw Error("grouping: expected the process's memory >= 0 (process_bytes = " +
                std::to_string(process_bytes) + ")");
  // A process that has not matched yet will still grow by the runtime's
  // warm-up in its first group (MatcherMemoryModel).
  if (process_bytes > 0) process_bytes += MatcherMemory().runtime_warmup_bytes;
  CheckSmallestGroupFits(block, options, matcher, process_bytes);
  GroupingPlan plan;
  plan.process_bytes = process_bytes;
  plan.strategy = options.strategy;
  plan.options = options;
  plan.matcher = matcher;
  plan.strips = DetectStrips(block);
  const BlockGeometry geometry = known_geometry ? *known_geometry : EstimateBlockGeometry(block);
  if (const std::string reason = NoSurfaceReason(block, geometry); !reason.empty()) {
    throw Error(reason);
  }
  const std::vector<Footprint> fp = Footprints(block, geometry);
  // The strategy's plan first, even for a block that is then kept whole: its
  // checks (tile cost, a block that does not look down) are the options'.
  if (options.strategy == GroupingStrategy::kStrip)
    PlanStrips(block, options, fp, &plan);
  else
    PlanFootprint(block, options, geometry, fp, &plan);
  ImageGroup all;
  all.images.resize(block.images.size());
  std::iota(all.images.begin(), all.images.end(), 0);
  all.memory = EstimateInProcess(block, all.images, matcher, process_bytes);
  if (static_cast<int>(all.images.size()) <= options.max_images &&
      all.memory.Total() <= options.memory_budget) {
    for (const int i : all.images) all.center += fp[i].center;
    all.center /= static_cast<double>(all.images.size());
    all.short_of_views = ShortOfViews(fp, all.images, matcher.min_image_num, all.images);
    plan.groups.assign(1, all);
    plan.ungrouped.clear();
    plan.single_group = true;
    return plan;
  }
  if (options.strategy == GroupingStrategy::kStrip) AddStripViews(block, options, fp, &plan);
  for (ImageGroup& g : plan.groups) {
    const std::vector<int> matched_in = g.MatchedIn();
    g.memory = EstimateInProcess(block, matched_in, matcher, process_bytes);
    g.short_of_views = ShortOfViews(fp, g.images, matcher.min_image_num, matched_in);
  }
  return plan;
}

}  // namespace sapmvs

#include "sapmvs/plan/grouping.h"
#include "sapmvs/util/byte_size.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <sstream>
#include <tuple>

#include "plan/grouping_internal.h"
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

std::string GroupNames(const Block& block, const std::vector<int>& ids) {
  std::string s;
  for (size_t k = 0; k < ids.size() && k < 4; ++k) s += (k ? ", " : "") + block.images[ids[k]].name;
  return ids.size() > 4 ? s + ", ..." : s;
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
        GroupNames(block, ids) + ": " + FormatBytes(mem.host_bytes) +
        (process_bytes > 0 ? " + the process before matching " + FormatBytes(process_bytes)
                           : std::string()) +
        "); raise the budget or match at a coarser level");
  }
}

// The paper's smallest group (Table 3: 16 images -> 6+6+4).
constexpr size_t kSmallestGroup = 4;

// Runs of at most k images, the last taking the remainder. A remainder
// under m moves the cuts back until every run has m (13 -> 5+4+4, not
// 6+6+1) when the strip has the images for it; otherwise a single image left
// at the end takes one from the run before it (k >= 3) or shares its last
// image (k = 2).
std::vector<std::vector<int>> CutRuns(const std::vector<int>& strip, size_t k, size_t m) {
  std::vector<std::vector<int>> runs;
  for (size_t i = 0; i < strip.size(); i += k)
    runs.emplace_back(strip.begin() + i, strip.begin() + std::min(i + k, strip.size()));
  const size_t r = runs.size();
  if (r >= 2 && runs.back().size() < m && strip.size() >= m * r) {
    std::vector<size_t> size(r, k);
    size.back() = strip.size() - k * (r - 1);
    for (size_t j = r - 1; j > 0 && size[j] < m; --j) {
      const size_t need = m - size[j];
      size[j] += need;
      size[j - 1] -= need;
    }
    runs.clear();
    size_t at = 0;
    for (const size_t n : size) {
      runs.emplace_back(strip.begin() + at, strip.begin() + at + n);
      at += n;
    }
    return runs;
  }
  if (r >= 2 && runs.back().size() == 1) {
    std::vector<int>& prev = runs[r - 2];
    runs.back().insert(runs.back().begin(), prev.back());
    if (prev.size() >= 3) prev.pop_back();
  }
  return runs;
}

// The runs of one strip, cut to fit the budget and each with the images a
// patch needs (groups of strip `s`).
void CutStrip(const Block& block, const GroupingOptions& o, const std::vector<int>& strip, int s,
              GroupingPlan* plan) {
  // One run length per strip keeps the paper's pattern (6+6+4) while the
  // budget allows, and shortens every run of the strip when it does not.
  std::vector<std::vector<int>> runs;
  for (int k = o.max_images; k >= 2; --k) {
    runs = CutRuns(strip, static_cast<size_t>(k), std::min<size_t>(kSmallestGroup, k));
    if (std::all_of(runs.begin(), runs.end(),
                    [&](const std::vector<int>& r) { return Fits(block, r, *plan); }))
      break;
  }
  // A run of fewer images than a patch needs matches nothing (a strip of
  // 17 cut 4+4+4+4+1 by the budget): it takes the strip images before it,
  // which the run before it matched too; the merge keeps one of the
  // duplicates.
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
    g.strip = s;
    plan->groups.push_back(std::move(g));
  }
}

// Strip strategy. A strip too short for a group of its own (a broken strip,
// a short cross strip) joins the nearest group with room for all of it, else
// is a group when a patch can be matched in it, else its images join the
// groups that see them best; so do the outliers (climb photos as views only:
// their GSD is not the strips', so the merge should not get their points).
void PlanStrips(const Block& block, const GroupingOptions& o, const std::vector<Footprint>& fp,
                GroupingPlan* plan) {
  const size_t smallest = std::min<size_t>(kSmallestGroup, o.max_images);
  std::vector<size_t> short_strips;
  for (size_t s = 0; s < plan->strips.size(); ++s) {
    if (plan->strips[s].size() < smallest)
      short_strips.push_back(s);
    else
      CutStrip(block, o, plan->strips[s], static_cast<int>(s), plan);
  }
  if (plan->groups.empty()) {
    // No strip structure (a terrestrial or convergent block, or one of a few
    // images): its images in block order are the one strip.
    std::vector<int> all(block.images.size());
    std::iota(all.begin(), all.end(), 0);
    CutStrip(block, o, all, -1, plan);
    for (ImageGroup& g : plan->groups) g.center = MeanCenter(fp, g.images);
    return;
  }
  for (ImageGroup& g : plan->groups) g.center = MeanCenter(fp, g.images);
  std::vector<int> joining;
  std::vector<bool> as_image;
  for (const size_t s : short_strips) {
    const std::vector<int>& strip = plan->strips[s];
    const Eigen::Vector2d c = MeanCenter(fp, strip);
    std::vector<size_t> order(plan->groups.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      return (plan->groups[a].center - c).squaredNorm() <
             (plan->groups[b].center - c).squaredNorm();
    });
    bool placed = false;
    for (const size_t gi : order) {
      ImageGroup& g = plan->groups[gi];
      std::vector<int> with = g.images;
      with.insert(with.end(), strip.begin(), strip.end());
      if (static_cast<int>(with.size()) > o.max_images || !Fits(block, with, *plan)) continue;
      g.images = std::move(with);
      g.center = MeanCenter(fp, g.images);
      placed = true;
      break;
    }
    if (!placed && static_cast<int>(strip.size()) >= std::max(2, plan->matcher.min_image_num) &&
        Fits(block, strip, *plan)) {
      ImageGroup g;
      g.images = strip;
      g.strip = static_cast<int>(s);
      g.center = c;
      plan->groups.push_back(std::move(g));
      placed = true;
    }
    for (const int i : strip) {
      if (placed) break;
      joining.push_back(i);
      as_image.push_back(true);
    }
  }
  for (const StripOutlier& out : plan->outliers) {
    joining.push_back(out.image);
    as_image.push_back(out.kind != OutlierKind::kClimb);
  }
  plan->ungrouped = JoinBestGroup(block, fp, joining, as_image, plan);
  TopUpSmallGroups(block, fp, smallest, plan);
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

// A group of fewer than `smallest` images (a corner of the block that few
// photos see: on the Caliterra flight a tile that 2 of its 75 photos reach)
// is matched by its neighbours when they can: its ground goes, as the merge
// gives it, to the nearest other centres, and each of the groups it goes to
// must hold all of its images and still fit with its tile grown over it.
// Centres stay where they are, so no other ground changes hands.
void AbsorbSmallGroups(const Block& block, const std::vector<Footprint>& fp, size_t smallest,
                       GroupingPlan* plan) {
  for (size_t k = 0; k < plan->groups.size();) {
    const ImageGroup& small = plan->groups[k];
    if (small.images.size() >= smallest || plan->groups.size() < 2) {
      ++k;
      continue;
    }
    std::vector<int> mine = small.images;
    std::sort(mine.begin(), mine.end());
    // Who takes each sample of the tile, and the tiles grown to hold them.
    std::map<size_t, ImageGroup> grown;
    bool can = true;
    for (int sy = 0; sy < kTileSamples && can; ++sy) {
      for (int sx = 0; sx < kTileSamples && can; ++sx) {
        const Eigen::Vector2d p =
            small.tile_min + Eigen::Vector2d((sx + 0.5) / kTileSamples, (sy + 0.5) / kTileSamples)
                                 .cwiseProduct(small.tile_max - small.tile_min);
        size_t to = k;
        for (size_t j = 0; j < plan->groups.size(); ++j) {
          if (j != k && (to == k || (plan->groups[j].center - p).squaredNorm() <
                                        (plan->groups[to].center - p).squaredNorm()))
            to = j;
        }
        auto it = grown.find(to);
        if (it == grown.end()) {
          std::vector<int> theirs = plan->groups[to].images;
          std::sort(theirs.begin(), theirs.end());
          can = std::includes(theirs.begin(), theirs.end(), mine.begin(), mine.end());
          it = grown.emplace(to, plan->groups[to]).first;
        }
        it->second.tile_min = it->second.tile_min.cwiseMin(p);
        it->second.tile_max = it->second.tile_max.cwiseMax(p);
      }
    }
    for (const auto& [j, g] : grown) can = can && Fits(block, g, fp, *plan);
    if (!can) {
      ++k;
      continue;
    }
    for (const auto& [j, g] : grown) {
      plan->groups[j].tile_min = g.tile_min;
      plan->groups[j].tile_max = g.tile_max;
    }
    plan->groups.erase(plan->groups.begin() + static_cast<long>(k));
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
  // Tiles up to 2 % longer than `side` rather than one more: a regular
  // flight's extent is close to a whole number of footprints, and a
  // centimetre of ground height either way (a DEM read at another cell)
  // would otherwise add or drop a row of tiles.
  const int nx = std::max(1, static_cast<int>(std::ceil(size.x() / side - 0.02)));
  const int ny = std::max(1, static_cast<int>(std::ceil(size.y() / side - 0.02)));
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
      // image that sees more of the tile, then to the more nadir one. The
      // view-only images follow by the same rule.
      ImageGroup g;
      g.tile_min = t0;
      g.tile_max = t0 + tile;
      const int target = std::min(o.tile_views, o.max_images);
      const std::vector<int> available = views;
      std::fill(views.begin(), views.end(), 0);
      std::vector<bool> taken(candidates.size(), false);
      auto pick = [&](int want, int goal, std::vector<int>* into) {
        while (static_cast<int>(into->size()) < want) {
          int best = -1;
          std::tuple<int, int, size_t, double> best_key{0, 0, 0, 0};
          for (size_t c = 0; c < candidates.size(); ++c) {
            if (taken[c]) continue;
            int gain = 0, second = 0;
            for (const int s : candidates[c].seen) {
              gain += views[s] < goal;
              second += views[s] < std::min(2, available[s]);
            }
            const std::tuple<int, int, size_t, double> key{second, gain, candidates[c].seen.size(),
                                                           candidates[c].nadir};
            if (gain > 0 && (best < 0 || key > best_key)) {
              ImageGroup with = g;
              (into == &g.images ? with.images : with.views).push_back(candidates[c].image);
              if (!Fits(block, with, fp, *plan)) continue;
              best = static_cast<int>(c);
              best_key = key;
            }
          }
          if (best < 0) return;
          taken[best] = true;
          into->push_back(candidates[best].image);
          for (const int s : candidates[best].seen) ++views[s];
        }
      };
      pick(o.max_images, target, &g.images);
      pick(o.tile_extra_views, target + o.tile_extra_views, &g.views);
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
        // Its images then take points on both tiles.
        ImageGroup both = e;
        both.tile_min = e.tile_min.cwiseMin(t0);
        both.tile_max = e.tile_max.cwiseMax(t0 + tile);
        if (!Fits(block, both, fp, *plan)) continue;
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
  AbsorbSmallGroups(block, fp, std::min<size_t>(kSmallestGroup, o.max_images), plan);
  // An image no tile chose (its ground better seen by others, or no ground
  // at all) still joins the group that sees it best, so that no image is
  // left out of the plan.
  std::vector<int> unused;
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i]) unused.push_back(static_cast<int>(i));
  plan->ungrouped = JoinBestGroup(block, fp, unused, std::vector<bool>(unused.size(), true), plan);
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
                                const MatcherOptions& matcher,
                                const std::vector<double>& cell_shares) {
  if (matcher.level < 0 || matcher.level > kMaxLevel)
    throw Error("memory estimate: level in 0.." + std::to_string(kMaxLevel) + " expected, got " +
                std::to_string(matcher.level));
  if (!cell_shares.empty() && cell_shares.size() != images.size())
    throw Error("memory estimate: " + std::to_string(images.size()) +
                " cell shares expected, got " + std::to_string(cell_shares.size()));
  const MatcherMemoryModel model = MatcherMemory();
  GroupMemory m;
  double load = 0;
  for (size_t k = 0; k < images.size(); ++k) {
    const int id = images[k];
    if (id < 0 || id >= static_cast<int>(block.images.size()))
      throw Error("memory estimate: image index " + std::to_string(id) + " is outside the block");
    const double share = cell_shares.empty() ? 1.0 : cell_shares[k];
    if (!(share >= 0 && share <= 1))
      throw Error("memory estimate: a cell share in [0, 1] expected, got " + std::to_string(share));
    const Camera& cam = block.images[id].camera;
    const Intrinsics in = cam.intrinsics().Scaled(std::ldexp(1.0, -matcher.level));
    const double pixels = static_cast<double>(in.width) * in.height;
    m.device_bytes += model.device_bytes_per_pixel * pixels;
    m.host_bytes +=
        (model.host_bytes_per_pixel + model.host_bytes_per_point_pixel * share) * pixels;
    load = std::max(load, 6.0 * cam.width() * cam.height());
  }
  const double wave = std::max(0, matcher.max_wave);
  m.device_bytes += wave * model.device_bytes_per_candidate;
  m.host_bytes += wave * (model.host_bytes_per_candidate + model.device_bytes_per_candidate);
  m.host_bytes += kImagesReadAtOnce * load;
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
  const BlockGeometry geometry = known_geometry ? *known_geometry : EstimateBlockGeometry(block);
  if (const std::string reason = NoSurfaceReason(block, geometry); !reason.empty()) {
    throw Error(reason);
  }
  StripDetection strips = DetectStrips(block, &geometry);
  plan.strips = std::move(strips.strips);
  plan.outliers = std::move(strips.outliers);
  const std::vector<Footprint> fp = Footprints(block, geometry);
  // Footprint tiles need ground under the images: a block that does not
  // look down (a facade, a convergent close-range block) is grouped along
  // its flight, or in block order, as the strip strategy groups it.
  if (plan.strategy == GroupingStrategy::kFootprint && !geometry.aerial) {
    plan.strategy = GroupingStrategy::kStrip;
  }
  // The strategy's plan first, even for a block that is then kept whole: its
  // checks (tile cost) are the options'.
  if (plan.strategy == GroupingStrategy::kStrip)
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
  if (plan.strategy == GroupingStrategy::kStrip) AddStripViews(block, options, fp, &plan);
  AddAngleViews(block, fp, &plan);
  for (ImageGroup& g : plan.groups) {
    const std::vector<int> matched_in = g.MatchedIn();
    g.memory = EstimateInProcess(block, g, fp, matcher, process_bytes);
    g.short_of_views = ShortOfViews(fp, g.images, matcher.min_image_num, matched_in);
  }
  return plan;
}

}  // namespace sapmvs

#include "match/propagation.h"

#include "match/footprint.h"
#include "match/ncc_score_reference.h"
#include "match/plane_refit.h"
#include "sapmvs/util/memory_use.h"
#include "sapmvs/util/parallel_for.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <numeric>
#include <unordered_map>

namespace sapmvs {
namespace {

// A cell is offered to at most this many candidates. One retry lets a cell
// that failed from one side succeed from another (a different parent plane);
// more only repeats work on cells that do not match (flat or occluded areas).
constexpr uint8_t kMaxCellTries = 2;

const int kDirections8[8][2] = {{1, 0}, {-1, 0}, {0, 1},  {0, -1},
                                {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};

}  // namespace

std::vector<std::pair<int, int>> WindowPixels(const cv::Mat& grey, int cx, int cy, int side,
                                              double sigma_color, double min_weight,
                                              const std::function<bool(int, int)>& barrier) {
  std::vector<std::pair<int, int>> out;
  if (cx < 0 || cy < 0 || cx >= grey.cols || cy >= grey.rows) return out;
  auto at = [&](int x, int y) { return static_cast<double>(grey.at<float>(y, x)); };
  // |d| <= reach keeps exp(-d^2 / 2 s^2) >= min_weight.
  double reach = std::numeric_limits<double>::infinity();
  if (sigma_color > 0 && min_weight > 0) {
    double centre[9];
    int n = 0;
    for (int y = std::max(0, cy - 1); y <= std::min(grey.rows - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(grey.cols - 1, cx + 1); ++x) {
        centre[n++] = at(x, y);
      }
    }
    const double s = NccWeightScale(centre, n, sigma_color);
    if (s > 0) reach = s * std::sqrt(-2.0 * std::log(std::min(1.0, min_weight)));
  }
  const double centre = at(cx, cy);
  const int h = side / 2;
  // 4-connected, so that an 8-connected edge line is a closed barrier.
  std::vector<uint8_t> seen(static_cast<size_t>(side) * side, 0);
  std::vector<std::pair<int, int>> stack = {{cx, cy}};
  seen[static_cast<size_t>(h) * side + h] = 1;
  while (!stack.empty()) {
    const auto [x, y] = stack.back();
    stack.pop_back();
    out.emplace_back(x, y);
    const int next[4][2] = {{x + 1, y}, {x - 1, y}, {x, y + 1}, {x, y - 1}};
    for (const auto& q : next) {
      const int lx = q[0] - cx + h, ly = q[1] - cy + h;
      if (lx < 0 || ly < 0 || lx >= side || ly >= side) continue;
      if (q[0] < 0 || q[1] < 0 || q[0] >= grey.cols || q[1] >= grey.rows) continue;
      uint8_t& s = seen[static_cast<size_t>(ly) * side + lx];
      if (s) continue;
      s = 1;
      if (std::abs(at(q[0], q[1]) - centre) > reach || barrier(q[0], q[1])) continue;
      stack.emplace_back(q[0], q[1]);
    }
  }
  return out;
}

Eigen::Vector3d IntersectPlane(const Camera& camera, const Eigen::Vector2d& uv,
                               const Eigen::Vector3d& c, const Eigen::Vector3d& n) {
  const Eigen::Vector3d ray = camera.Ray(uv);
  const double den = n.dot(ray);
  const double t = std::abs(den) > 1e-12 ? n.dot(c - camera.center()) / den : -1.0;
  if (!(t > 0)) return Eigen::Vector3d::Constant(std::nan(""));
  return camera.center() + t * ray;
}

int Propagator::Grid::Index(const Eigen::Vector2d& uv, int cell) const {
  const int x = static_cast<int>(std::floor((uv.x() + 0.5) / cell));
  const int y = static_cast<int>(std::floor((uv.y() + 0.5) / cell));
  if (x < 0 || y < 0 || x >= cols || y >= rows) return -1;
  return y * cols + x;
}

Propagator::Propagator(const MatchGroupData& group, const MatcherOptions& options,
                       PatchEngine& engine)
    : group_(group), options_(options), engine_(&engine) {
  const int cs = options_.cell_size;
  for (const MatchImage& im : group_.images) {
    Grid g;
    g.cols = (im.camera.width() + cs - 1) / cs;
    g.rows = (im.camera.height() + cs - 1) / cs;
    g.owner.assign(static_cast<size_t>(g.cols) * g.rows, -1);
    g.tries.assign(g.owner.size(), 0);
    grids_.push_back(std::move(g));
  }
  seed_depths_.resize(group_.images.size());
  beyond_views_.resize(group_.images.size());
  for (size_t r = 0; r < group_.images.size(); ++r) {
    if (!group_.images[r].reference) continue;
    const std::vector<int>& views = group_.images[r].views;
    for (size_t i = 0; i < group_.images.size(); ++i) {
      if (i != r && group_.images[i].reference &&
          std::find(views.begin(), views.end(), static_cast<int>(i)) == views.end()) {
        beyond_views_[r].push_back(static_cast<int>(i));
      }
    }
  }
  // A point lies in a reference cell its patch owns, one per pixel (one
  // centre per cell in pmvs mode), so the cells bound the points. Reserving
  // the bound once replaces growing by copies: on `city` those copies, and
  // the page faults of each new array, were half of the main thread's work
  // in the waves, with the other core idle, and held the old array beside
  // the new. An array this large is mapped (MemoryUse), so only the pages
  // written take memory, unless an address-space or data limit or strict
  // overcommit counts the whole reservation: there, and where a cell freed
  // by Prune holds more, Emit grows the array.
  const size_t per_cell =
      options_.mode == MatchMode::kPmvs ? 1 : static_cast<size_t>(cs) * static_cast<size_t>(cs);
  size_t bound = 0;
  for (const Grid& g : grids_) bound += g.owner.size() * per_cell;
  if (UnwrittenMemoryIsFree()) {
    try {
      points_.reserve(bound);
    } catch (const std::bad_alloc&) {
    }
  }
}

bool Propagator::IsBarrier(int image, int x, int y, const AcceptedPatch& patch) const {
  if (edges_.empty() || edges_[image].matched.empty()) return false;
  if (!edges_[image].matched.at<uint8_t>(y, x)) return false;
  const auto found = edges_[image].points.find(y * edges_[image].matched.cols + x);
  if (found == edges_[image].points.end()) return false;
  const Eigen::Vector3d p = found->second.cast<double>();
  const double footprint = Footprint(group_.images[image].camera, patch.center);
  const double off_plane = std::abs(patch.normal.dot(p - patch.center));
  return off_plane > options_.depth_tolerance * footprint;
}

Propagator::EmitPlan Propagator::PlanEmit(const AcceptedPatch& patch) const {
  EmitPlan plan;
  const Camera& cam = group_.images[patch.ref].camera;
  const Grid& grid = grids_[patch.ref];
  const int cs = options_.cell_size;
  const Eigen::Vector2d uv0 = cam.Project(patch.center);
  if (PmvsStyle() || patch.size <= 1) {
    DensePoint d;
    d.x = patch.center;
    d.uv = uv0.cast<float>();
    plan.points.push_back(d);
    plan.ref_cells.push_back(grid.Index(uv0, cs));
  } else {
    const int cx = static_cast<int>(std::lround(uv0.x()));
    const int cy = static_cast<int>(std::lround(uv0.y()));
    const auto pixels = WindowPixels(
        group_.images[patch.ref].grey, cx, cy, patch.size, options_.ncc_sigma_color,
        options_.emit_min_weight, [&](int x, int y) { return IsBarrier(patch.ref, x, y, patch); });
    for (const auto& [x, y] : pixels) {
      const Eigen::Vector3d p =
          IntersectPlane(cam, Eigen::Vector2d(x, y), patch.center, patch.normal);
      if (!p.allFinite()) continue;
      DensePoint d;
      d.x = p;
      d.uv = Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y));
      plan.points.push_back(d);
      plan.ref_cells.push_back(grid.Index(Eigen::Vector2d(x, y), cs));
    }
  }
  // Projected here, on all cores, rather than in Emit, which claims in
  // order on one: there they were most of the serial time of a wave.
  const size_t n = plan.points.size();
  plan.view_cells.assign(patch.views.size() * n, -1);
  for (size_t v = 0; v < patch.views.size(); ++v) {
    const Camera& vc = group_.images[patch.views[v]].camera;
    const Grid& vg = grids_[patch.views[v]];
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d& x = plan.points[k].x;
      if (vc.Depth(x) > 0) plan.view_cells[v * n + k] = vg.Index(vc.Project(x), cs);
    }
  }
  // In a group larger than a view list, the other images that see the
  // patch's ground would match it again as references: the Caliterra flight
  // as one group of 75 images gave 7.67 M points where its 18 groups of 8
  // kept 2.97 M, in 175 s against 60. Their cells are claimed too, where the
  // patch faces them as a view would (view_angle_deg).
  const std::vector<int>& beyond = beyond_views_[patch.ref];
  if (beyond.empty()) return plan;
  const double cos_max = std::cos(options_.view_angle_deg * M_PI / 180.0);
  const Eigen::Vector3d& ref_center = cam.center();
  double widest = 0;
  for (const int v : patch.views) {
    widest = std::max(
        widest, TriangulationAngleDeg(ref_center, group_.images[v].camera.center(), patch.center));
  }
  // The patch's views come from the reference's list and the group's
  // view-only images, so none of them is in `beyond`.
  for (const int i : beyond) {
    const Camera& c = group_.images[i].camera;
    if (!SeesPatch(c, patch.center, patch.normal, cos_max, 0)) continue;
    // And only within the widest angle its views make with the reference:
    // beyond, the image may see something else there (a roof over a wall's
    // foot), and claimed there, `city` as one group of 18 images lost 1.0
    // point of its truth's coverage, as it did when they scored the patch
    // (NCC).
    if (TriangulationAngleDeg(ref_center, c.center(), patch.center) > widest) continue;
    plan.covers.push_back(i);
    const Grid& g = grids_[i];
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d& x = plan.points[k].x;
      plan.cover_cells.push_back(c.Depth(x) > 0 ? g.Index(c.Project(x), cs) : -1);
    }
  }
  return plan;
}

bool Propagator::Emit(const AcceptedPatch& patch, const EmitPlan& plan) {
  const int id = static_cast<int>(patches_.size());
  Grid& grid = grids_[patch.ref];
  const size_t first_point = points_.size();
  // A quarter more at a time, not push_back's double: the points are a
  // group's largest array, and doubling left up to half of it unused through
  // the filter (20 MB on `city`) and held three times their size while it
  // copied them.
  if (first_point + plan.points.size() > points_.capacity()) {
    points_.reserve(std::max(first_point + plan.points.size(), first_point + first_point / 4));
  }
  std::vector<uint8_t>& emitted = emit_scratch_;
  emitted.assign(plan.points.size(), 0);
  for (size_t k = 0; k < plan.points.size(); ++k) {
    const int cell = plan.ref_cells[k];
    if (cell < 0 || (grid.owner[cell] != -1 && grid.owner[cell] != id)) continue;
    grid.owner[cell] = id;
    points_.push_back(plan.points[k]);
    points_.back().patch = id;
    emitted[k] = 1;
  }
  if (points_.size() == first_point) return false;
  emitted_ += static_cast<long>(points_.size() - first_point);
  // The views' cells where the points land are covered too, so the same
  // ground is not matched again with another reference.
  const size_t n = plan.points.size();
  for (size_t v = 0; v < patch.views.size(); ++v) {
    Grid& vg = grids_[patch.views[v]];
    for (size_t k = 0; k < n; ++k) {
      const int cell = plan.view_cells[v * n + k];
      if (emitted[k] && cell >= 0 && vg.owner[cell] == -1) vg.owner[cell] = id;
    }
  }
  for (size_t c = 0; c < plan.covers.size(); ++c) {
    Grid& g = grids_[plan.covers[c]];
    for (size_t k = 0; k < n; ++k) {
      const int cell = plan.cover_cells[c * n + k];
      if (emitted[k] && cell >= 0 && g.owner[cell] == -1) g.owner[cell] = id;
    }
  }
  // Kept per patch once any patch has covers, for Release and Prune.
  if (!covers_.empty() || !plan.covers.empty()) {
    covers_.resize(static_cast<size_t>(id) + 1);
    covers_[id] = plan.covers;
  }
  patches_.push_back(patch);
  cut_.push_back(0);
  return true;
}

void Propagator::Offer(const AcceptedPatch& patch, const Eigen::Vector2d& q,
                       std::vector<PatchCandidate>* front, int image) {
  if (image < 0) image = patch.ref;
  const Camera& cam = group_.images[image].camera;
  Grid& grid = grids_[image];
  if (!cam.InImage(q, options_.window_size / 2 + 1)) return;
  const int cell = grid.Index(q, options_.cell_size);
  if (cell < 0 || grid.owner[cell] != -1 || grid.tries[cell] >= kMaxCellTries) return;
  const Eigen::Vector3d c = IntersectPlane(cam, q, patch.center, patch.normal);
  if (!c.allFinite() || !InRegion(c)) return;
  ++grid.tries[cell];
  PatchCandidate cand;
  cand.center = c;
  cand.normal = patch.normal;
  cand.ref = image;
  cand.has_parent = true;
  cand.parent_center = patch.center;
  cand.parent_normal = patch.normal;
  cand.parent_score = patch.score;
  front->push_back(cand);
}

void Propagator::Grid::Beside(int cell, std::vector<int>* out) const {
  if (cell < 0) return;
  const int gx = cell % cols, gy = cell / cols;
  for (int d = 0; d < 4; ++d) {
    const int nx = gx + kDirections8[d][0], ny = gy + kDirections8[d][1];
    if (nx >= 0 && ny >= 0 && nx < cols && ny < rows) out->push_back(ny * cols + nx);
  }
}

Eigen::Vector2d Propagator::Grid::Centre(int cell, int cs) const {
  return Eigen::Vector2d((cell % cols + 0.5) * cs - 0.5, (cell / cols + 0.5) * cs - 0.5);
}

void Propagator::OfferBeside(const AcceptedPatch& patch, int cell,
                             std::vector<PatchCandidate>* front) {
  const Grid& grid = grids_[patch.ref];
  std::vector<int>& beside = beside_scratch_;
  beside.clear();
  grid.Beside(cell, &beside);
  for (const int next : beside) Offer(patch, grid.Centre(next, options_.cell_size), front);
}

void Propagator::OfferAtCells(const AcceptedPatch& patch, int image, std::vector<int>* cells,
                              std::vector<PatchCandidate>* front) {
  std::sort(cells->begin(), cells->end());
  cells->erase(std::unique(cells->begin(), cells->end()), cells->end());
  for (const int cell : *cells) {
    Offer(patch, grids_[image].Centre(cell, options_.cell_size), front, image);
  }
}

void Propagator::OfferInViews(const AcceptedPatch& patch, const DensePoint* first,
                              const DensePoint* last, std::vector<PatchCandidate>* front) {
  const int cs = options_.cell_size;
  const Eigen::Vector3d& ref_center = group_.images[patch.ref].camera.center();
  std::vector<int>& beside = beside_scratch_;
  for (const int v : patch.views) {
    const MatchImage& view = group_.images[v];
    // A view-only image (another strip's) takes no patch as reference; a
    // view near the reference's ray sees the same rim.
    if (!view.reference) continue;
    if (TriangulationAngleDeg(ref_center, view.camera.center(), patch.center) <
        2 * options_.max_angle_deg) {
      continue;
    }
    const Grid& grid = grids_[v];
    beside.clear();
    for (const DensePoint* d = first; d != last; ++d) {
      if (view.camera.Depth(d->x) > 0) {
        grid.Beside(grid.Index(view.camera.Project(d->x), cs), &beside);
      }
    }
    OfferAtCells(patch, v, &beside, front);
  }
}

void Propagator::GrowAsPmvs(PatchEngine& engine) {
  engine_ = &engine;
  grows_as_pmvs_ = true;
}

void Propagator::Expand(int patch_index, std::vector<PatchCandidate>* front) {
  const AcceptedPatch& patch = patches_[patch_index];
  const Camera& cam = group_.images[patch.ref].camera;
  const Eigen::Vector2d uv0 = cam.Project(patch.center);
  if (PmvsStyle()) {
    OfferBeside(patch, grids_[patch.ref].Index(uv0, options_.cell_size), front);
    // A pmvs pass's patch grows in its views at every wave, as PMVS2's
    // does: from the pass's start alone, walls that only an oblique view
    // sees wide stayed half bare (on `city` 77 % of PMVS2's right points on
    // walls covered, against 88 % by a second PMVS2 run). It emits its
    // centre alone (PlanEmit).
    if (grows_as_pmvs_) {
      DensePoint centre;
      centre.x = patch.center;
      OfferInViews(patch, &centre, &centre + 1, front);
    }
  } else {
    // The paper's "just beyond its extent": the new centre two pixels past
    // the parent's edge, its window overlapping the parent's last pixels.
    // Centring the new window wholly beyond the parent (a step longer by
    // hw - 1) left the ground between a patch and a wall or crown untried
    // (`small` at level 0: 85.6 % of the seen cells covered against 87.1 %).
    // With refill_cut, a patch the refit cut back expands from its centre
    // into the pixels it gave up. Always doing so gained 1 point of coverage
    // on `small` and `city` but took 29 % longer on `campus`, where most
    // patches are cut, for none.
    const bool cut = options_.refill_cut && cut_[patch_index];
    const int step = (cut ? kUnfittedReach : patch.size / 2) + 2;
    const Eigen::Vector2d c(std::round(uv0.x()), std::round(uv0.y()));
    for (const auto& d : kDirections8) Offer(patch, c + step * Eigen::Vector2d(d[0], d[1]), front);
  }
}

std::vector<int> Propagator::AcceptBatch(std::vector<std::optional<AcceptedPatch>>& results) {
  std::vector<int> order;
  for (size_t i = 0; i < results.size(); ++i) {
    if (results[i]) order.push_back(static_cast<int>(i));
  }
  // Better patches claim contested cells first.
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return results[a]->score > results[b]->score; });
  // The points and cells a patch would claim depend only on the patch, so
  // they are computed on all cores; the claims, which depend on the order,
  // stay in order. In chunks, so that a wave of large patches does not hold
  // all its plans at once.
  constexpr size_t kChunk = 256;
  std::vector<int> accepted;
  std::vector<EmitPlan> plans(std::min(order.size(), kChunk));
  for (size_t b = 0; b < order.size(); b += kChunk) {
    const int n = static_cast<int>(std::min(order.size() - b, kChunk));
    ParallelFor(
        n, [&](long j) { plans[j] = PlanEmit(*results[order[b + j]]); }, 4);
    for (int j = 0; j < n; ++j) {
      if (Emit(*results[order[b + j]], plans[j])) accepted.push_back(order[b + j]);
    }
  }
  return accepted;
}

void Propagator::RunSeeds(const std::vector<SeedFeature>& seeds,
                          const std::function<void(long, long, long)>& on_rank) {
  std::vector<uint8_t> done(seeds.size(), 0);
  const size_t first_patch = patches_.size();
  for (int rank = 0; rank < options_.candidates_per_feature; ++rank) {
    std::vector<PatchCandidate> batch;
    std::vector<int> which;
    for (size_t s = 0; s < seeds.size(); ++s) {
      if (done[s] || rank >= static_cast<int>(seeds[s].candidates.size())) continue;
      if (!CellFree(seeds[s].image, seeds[s].uv)) continue;
      if (!InRegion(seeds[s].candidates[rank].center)) continue;
      batch.push_back(seeds[s].candidates[rank]);
      which.push_back(static_cast<int>(s));
    }
    if (batch.empty()) break;
    seeds_tried_ += static_cast<long>(batch.size());
    for (size_t b = 0; b < batch.size(); b += options_.max_wave) {
      const size_t e = std::min(batch.size(), b + options_.max_wave);
      std::vector<PatchCandidate> part(batch.begin() + b, batch.begin() + e);
      auto results = engine_->Evaluate(part);
      for (const int i : AcceptBatch(results)) {
        done[which[b + i]] = 1;
        ++seeds_accepted_;
      }
    }
    if (on_rank) on_rank(rank + 1, options_.candidates_per_feature, seeds_accepted_);
  }
  for (size_t p = first_patch; p < patches_.size(); ++p) {
    const Camera& cam = group_.images[patches_[p].ref].camera;
    seed_depths_[patches_[p].ref].push_back(cam.Depth(patches_[p].center));
    Expand(static_cast<int>(p), &front_);
  }
}

bool Propagator::CellFree(int image, const Eigen::Vector2d& uv) const {
  const int cell = grids_[image].Index(uv, options_.cell_size);
  return cell >= 0 && grids_[image].owner[cell] == -1;
}

void Propagator::Release(const DensePoint& d) {
  const int cs = options_.cell_size;
  auto free_cell = [&](Grid& grid, int cell) {
    if (cell < 0 || grid.owner[cell] != d.patch) return;
    grid.owner[cell] = -1;
    grid.tries[cell] = options_.refill_cut ? 0 : kMaxCellTries - 1;
  };
  const AcceptedPatch& patch = patches_[d.patch];
  Grid& ref = grids_[patch.ref];
  free_cell(ref, ref.Index(d.uv.cast<double>(), cs));
  ForEachClaimImage(d.patch, [&](int v) {
    const Camera& vc = group_.images[v].camera;
    if (vc.Depth(d.x) > 0) free_cell(grids_[v], grids_[v].Index(vc.Project(d.x), cs));
  });
}

long Propagator::RefitPlanes() {
  if (options_.mode != MatchMode::kSapmvs || options_.refit_neighbours <= 0) return 0;
  std::vector<uint8_t> alive(patches_.size(), 0);
  for (const DensePoint& d : points_) alive[d.patch] = 1;
  const std::vector<Eigen::Vector3d> fitted = FitPatchNormals(group_, options_, patches_, alive);
  std::vector<Eigen::Vector2d> centre_uv(patches_.size());
  for (size_t p = 0; p < patches_.size(); ++p) {
    if (!alive[p]) continue;
    if (!fitted[p].isZero()) patches_[p].normal = fitted[p];
    centre_uv[p] = group_.images[patches_[p].ref].camera.Project(patches_[p].center);
  }
  // Each point's fate and new position depend on its patch only, so they
  // are decided on all cores; a point that is dropped keeps its old
  // position, from which Release finds the cells it owns.
  enum Fate : uint8_t { kKeep, kCut, kNoPoint };
  std::vector<uint8_t> fate(points_.size(), kKeep);
  const long n = static_cast<long>(points_.size());
  ParallelFor(
      n,
      [&](long i) {
        DensePoint& d = points_[i];
        const AcceptedPatch& patch = patches_[d.patch];
        if (fitted[d.patch].isZero()) {
          const Eigen::Vector2d off = d.uv.cast<double>() - centre_uv[d.patch];
          // Pixel uv lies within kUnfittedReach of the rounded centre.
          if (off.cwiseAbs().maxCoeff() > kUnfittedReach + 0.5) fate[i] = kCut;
        } else {
          const Eigen::Vector3d x = IntersectPlane(group_.images[patch.ref].camera,
                                                   d.uv.cast<double>(), patch.center, patch.normal);
          if (x.allFinite()) {
            d.x = x;
          } else {
            fate[i] = kNoPoint;
          }
        }
      },
      1024);
  const size_t before = points_.size();
  size_t out = 0;
  std::vector<int> newly_cut;
  for (size_t i = 0; i < points_.size(); ++i) {
    const DensePoint d = points_[i];
    if (fate[i] == kCut) {
      if (!cut_[d.patch]) newly_cut.push_back(d.patch);
      cut_[d.patch] = 1;
    }
    if (fate[i] != kKeep) {
      Release(d);
      continue;
    }
    points_[out++] = d;
  }
  points_.resize(out);
  // The pages past what is kept would stay resident through the filter, which
  // comes next and makes the group's peak (`city`: 541k -> 447k points).
  ReleaseUnusedCapacity(points_);
  // The ground the cut patches gave up is open to their expansion from the
  // centre (Expand's step for a cut patch) and to their neighbours'.
  if (options_.refill_cut) {
    for (const int p : newly_cut) Expand(p, &front_);
  }
  return static_cast<long>(before - out);
}

void Propagator::Prune(const std::vector<bool>& keep) {
  const int cs = options_.cell_size;
  // In place: a second vector of the kept points doubled the points' memory
  // at every pass.
  size_t out = 0;
  for (size_t i = 0; i < points_.size(); ++i) {
    if (keep[i]) points_[out++] = points_[i];
  }
  points_.resize(out);
  ReleaseUnusedCapacity(points_);  // as in RefitPlanes
  std::vector<std::vector<int>> before(grids_.size());
  for (size_t g = 0; g < grids_.size(); ++g) {
    before[g].swap(grids_[g].owner);
    grids_[g].owner.assign(before[g].size(), -1);
  }
  // Cells are owned again exactly as Emit owned them: the reference cell of
  // each point, and the view cells its points land in.
  std::vector<uint8_t> alive(patches_.size(), 0);
  for (const DensePoint& d : points_) {
    alive[d.patch] = 1;
    Grid& grid = grids_[patches_[d.patch].ref];
    const int cell = grid.Index(d.uv.cast<double>(), cs);
    if (cell >= 0) grid.owner[cell] = d.patch;
  }
  // The view cells are projected on all cores and claimed in point order (the
  // first claim holds), a chunk of points at a time.
  constexpr size_t kChunk = 65536;
  std::vector<size_t> offset;
  std::vector<int> view_cells;
  for (size_t first = 0; first < points_.size(); first += kChunk) {
    const size_t n = std::min(kChunk, points_.size() - first);
    offset.assign(n + 1, 0);
    for (size_t i = 0; i < n; ++i) {
      const int p = points_[first + i].patch;
      offset[i + 1] =
          offset[i] + patches_[p].views.size() + (covers_.empty() ? 0 : covers_[p].size());
    }
    view_cells.assign(offset[n], -1);
    ParallelFor(
        static_cast<long>(n),
        [&](long i) {
          const DensePoint& d = points_[first + i];
          size_t j = offset[i];
          ForEachClaimImage(d.patch, [&](int v) {
            const Camera& vc = group_.images[v].camera;
            if (vc.Depth(d.x) > 0) view_cells[j] = grids_[v].Index(vc.Project(d.x), cs);
            ++j;
          });
        },
        256);
    for (size_t i = 0; i < n; ++i) {
      const DensePoint& d = points_[first + i];
      size_t j = offset[i];
      ForEachClaimImage(d.patch, [&](int v) {
        const int cell = view_cells[j++];
        if (cell >= 0 && grids_[v].owner[cell] == -1) grids_[v].owner[cell] = d.patch;
      });
    }
  }
  for (size_t g = 0; g < grids_.size(); ++g) {
    for (size_t c = 0; c < before[g].size(); ++c) {
      if (before[g][c] != -1 && grids_[g].owner[c] == -1) grids_[g].tries[c] = 0;
    }
  }
  front_.clear();
  front_head_ = 0;
  if (grows_as_pmvs_) {
    // Every point's rim: an adaptive patch's centre lies among its own
    // points, whose cells it covers. A patch offers each cell beside its
    // points once (its points are stored together), not once per point
    // beside it: up to four times the same candidate, and a second try
    // (kMaxCellTries) spent on the same plane. Then the rims in its views
    // (OfferInViews), as each new patch's at every wave (Expand).
    std::vector<int>& beside = beside_scratch_;  // the cells beside one patch's points
    for (size_t i = 0; i < points_.size();) {
      const size_t first = i;
      const int id = points_[i].patch;
      const AcceptedPatch& patch = patches_[id];
      const Grid& grid = grids_[patch.ref];
      beside.clear();
      for (; i < points_.size() && points_[i].patch == id; ++i) {
        grid.Beside(grid.Index(points_[i].uv.cast<double>(), cs), &beside);
      }
      OfferAtCells(patch, patch.ref, &beside, &front_);
      OfferInViews(patch, points_.data() + first, points_.data() + i, &front_);
    }
    return;
  }
  for (size_t p = 0; p < patches_.size(); ++p) {
    if (alive[p]) Expand(static_cast<int>(p), &front_);
  }
}

std::vector<PatchCandidate> Propagator::Crowded(std::vector<PatchCandidate>* wave,
                                                const std::vector<Eigen::Vector2d>& pixels) const {
  const int r = std::max(1, options_.window_size / 2);
  // Kept centres by (image, block of r x r pixels): a clash lies in the
  // candidate's block or one of the 8 around it. Each block's centres are a
  // list through `next` (-1 ends it), in place of a vector per block, whose
  // allocations were most of this pass.
  std::unordered_map<uint64_t, int> block_head;
  block_head.reserve(wave->size());
  std::vector<int> next;
  std::vector<Eigen::Vector2f> centres;
  auto key = [](int image, int bx, int by) {
    return static_cast<uint64_t>(image) << 42 ^ static_cast<uint64_t>(by + (1 << 20)) << 21 ^
           static_cast<uint64_t>(bx + (1 << 20));
  };
  std::vector<PatchCandidate> now, later;
  for (size_t i = 0; i < wave->size(); ++i) {
    PatchCandidate& c = (*wave)[i];
    const Eigen::Vector2f uv = pixels[i].cast<float>();
    const int bx = static_cast<int>(std::floor(uv.x() / r));
    const int by = static_cast<int>(std::floor(uv.y() / r));
    bool clash = false;
    for (int dy = -1; dy <= 1 && !clash; ++dy) {
      for (int dx = -1; dx <= 1 && !clash; ++dx) {
        const auto found = block_head.find(key(c.ref, bx + dx, by + dy));
        if (found == block_head.end()) continue;
        for (int k = found->second; k >= 0; k = next[k]) {
          const Eigen::Vector2f& o = centres[k];
          if (std::abs(o.x() - uv.x()) < r && std::abs(o.y() - uv.y()) < r) {
            clash = true;
            break;
          }
        }
      }
    }
    if (clash) {
      later.push_back(std::move(c));
    } else {
      // Pushed at the list's head: the order within a block does not
      // change whether one of them clashes.
      const auto it = block_head.try_emplace(key(c.ref, bx, by), -1).first;
      next.push_back(it->second);
      centres.push_back(uv);
      it->second = static_cast<int>(centres.size()) - 1;
      now.push_back(std::move(c));
    }
  }
  wave->swap(now);
  return later;
}

void Propagator::RunWaves(const std::function<void(long, long, long)>& on_wave) {
  // The front's pending candidates are front_[front_head_, end): a wave
  // taken from its head only moves the head. Erased from the vector, each
  // wave moved all the rest (3 GB of candidates in Herz-Jesu-P8's pmvs pass).
  while (front_.size() > front_head_ && (options_.max_waves == 0 || waves_ < options_.max_waves)) {
    // Taken back once the spent head is as long as what is pending: each
    // candidate is then moved a bounded number of times.
    if (front_head_ >= front_.size() - front_head_) {
      front_.erase(front_.begin(), front_.begin() + static_cast<std::ptrdiff_t>(front_head_));
      front_head_ = 0;
    }
    std::vector<PatchCandidate> wave;
    const size_t max_wave = static_cast<size_t>(options_.max_wave);
    if (front_.size() - front_head_ <= max_wave) {
      if (front_head_ == 0) {
        wave.swap(front_);
      } else {
        wave.assign(front_.begin() + static_cast<std::ptrdiff_t>(front_head_), front_.end());
        front_.clear();
      }
      front_head_ = 0;
    } else {
      // Oldest first, so the front advances evenly.
      const auto head = front_.begin() + static_cast<std::ptrdiff_t>(front_head_);
      wave.assign(head, head + static_cast<std::ptrdiff_t>(max_wave));
      front_head_ += max_wave;
    }
    // Drop candidates whose cell was covered since they were queued, their
    // projections on all cores: the waves' own host work is serial, and the
    // device waits for it. Each centre's pixel is kept for Crowded.
    std::vector<Eigen::Vector2d> pixel(wave.size());
    std::vector<uint8_t> covered(wave.size());
    ParallelFor(
        static_cast<long>(wave.size()),
        [&](long i) {
          const PatchCandidate& c = wave[i];
          pixel[i] = group_.images[c.ref].camera.Project(c.center);
          covered[i] = !CellFree(c.ref, pixel[i]);
        },
        1024);
    std::vector<size_t> open;
    for (size_t i = 0; i < wave.size(); ++i) {
      if (!covered[i]) open.push_back(i);
    }
    if (open.empty()) continue;
    // Best parent first; the candidates and their pixels gathered in that
    // order.
    std::stable_sort(open.begin(), open.end(), [&](size_t a, size_t b) {
      return wave[a].parent_score > wave[b].parent_score;
    });
    std::vector<PatchCandidate> sorted;
    std::vector<Eigen::Vector2d> sorted_pixel;
    sorted.reserve(open.size());
    sorted_pixel.reserve(open.size());
    for (const size_t i : open) {
      sorted.push_back(std::move(wave[i]));
      sorted_pixel.push_back(pixel[i]);
    }
    wave.swap(sorted);
    // The crowded ones go back ahead of everything pending, in the head's
    // spent room when it holds them.
    std::vector<PatchCandidate> later = Crowded(&wave, sorted_pixel);
    if (later.size() <= front_head_) {
      front_head_ -= later.size();
      std::move(later.begin(), later.end(),
                front_.begin() + static_cast<std::ptrdiff_t>(front_head_));
    } else {
      front_.insert(front_.begin() + static_cast<std::ptrdiff_t>(front_head_),
                    std::make_move_iterator(later.begin()), std::make_move_iterator(later.end()));
    }
    ++waves_;
    candidates_ += static_cast<long>(wave.size());
    largest_wave_ = std::max(largest_wave_, static_cast<long>(wave.size()));
    auto results = engine_->Evaluate(wave);
    const size_t before = patches_.size();
    AcceptBatch(results);
    for (size_t p = before; p < patches_.size(); ++p) Expand(static_cast<int>(p), &front_);
    if (on_wave) on_wave(waves_, static_cast<long>(wave.size()), static_cast<long>(points_.size()));
  }
  // The front's largest size stays allocated otherwise, through the filter.
  if (front_.size() == front_head_) {
    std::vector<PatchCandidate>().swap(front_);
    front_head_ = 0;
  }
}

}  // namespace sapmvs

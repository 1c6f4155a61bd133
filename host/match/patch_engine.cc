#include "match/patch_engine.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>

#include "match/footprint.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/parallel_for.h"
#include "sapmvs/util/thread_count.h"

namespace sapmvs {
namespace {

// float32 rounding of a refined normal's cosine to its reference ray.
constexpr double kRimSlack = 1e-5;

}  // namespace

bool Faces(const Camera& camera, const Eigen::Vector3d& c, const Eigen::Vector3d& n,
           double cos_max) {
  return n.dot((camera.center() - c).normalized()) >= cos_max;
}

bool SeesPatch(const Camera& camera, const Eigen::Vector3d& c, const Eigen::Vector3d& n,
               double cos_max, double margin) {
  return camera.Depth(c) > 0 && camera.InImage(camera.Project(c), margin) &&
         Faces(camera, c, n, cos_max);
}

WindowGrid SampledWindow(int side, int window_size, double max_step) {
  const int half = side / 2;
  if (side <= window_size || half == 0) return {side, 1.0};
  // A hair under max_step first, so that a spacing of exactly max_step is
  // not pushed to one more sample by rounding.
  const int intervals = static_cast<int>(std::ceil(half / max_step - 1e-9));
  return {2 * intervals + 1, static_cast<double>(half) / intervals};
}

namespace {

// The NCC sample weights (MatcherOptions::ncc_sigma_color; 0 in pmvs mode).
double SigmaColorOf(const MatcherOptions& options) {
  return options.mode == MatchMode::kSapmvs ? options.ncc_sigma_color : 0.0;
}

// The refinement searches only normals the reference sees within
// view_angle_deg, as PMVS2's does: a search free to leave that cone ended
// beyond it on ground seen at grazing angles, and the patch was rejected.
double RefineMaxAngleOf(const MatcherOptions& options) {
  return std::min(options.view_angle_deg, 89.0);
}

PatchRefinerOptions RefineOptionsOf(const MatcherOptions& options) {
  PatchRefinerOptions ro;
  ro.patch_size = options.window_size;
  ro.max_angle_deg = RefineMaxAngleOf(options);
  ro.sigma_color = SigmaColorOf(options);
  return ro;
}

PatchRefinerOptions ExpansionOptionsOf(const MatcherOptions& options, PatchEngine::Role role) {
  PatchRefinerOptions ro = RefineOptionsOf(options);
  ro.depth_step = kExpansionRefineDepthStep;
  ro.angle_step_deg = kExpansionRefineAngleStepDeg;
  ro.max_halvings =
      role == PatchEngine::Role::kOneCellPass ? kOneCellRefineHalvings : kExpansionRefineHalvings;
  if (role == PatchEngine::Role::kOneCellPass) ro.iterations = kOneCellRefineIterations;
  return ro;
}

// By patch side: the polish of each larger adaptive size (sapmvs mode).
std::map<int, PatchRefinerOptions> PolishOptionsOf(const MatcherOptions& options) {
  std::map<int, PatchRefinerOptions> polish;
  if (options.mode != MatchMode::kSapmvs) return polish;
  for (const int size : options.adaptive_sizes) {
    if (size <= options.window_size) continue;
    PatchRefinerOptions po;
    const WindowGrid grid = SampledWindow(size, options.window_size, options.adaptive_sample_step);
    po.patch_size = grid.samples;
    po.sample_step = grid.step;
    po.iterations = kPolishIterations;
    po.depth_step = kPolishDepthStep;
    po.angle_step_deg = kPolishAngleStepDeg;
    po.max_angle_deg = RefineMaxAngleOf(options);
    po.sigma_color = SigmaColorOf(options);
    po.work_group_size = kPolishWorkGroupSize;
    polish[size] = po;
  }
  return polish;
}

NccScorerOptions ScoreOptionsOf(const MatcherOptions& options, int size) {
  NccScorerOptions so;
  so.patch_size = size;
  so.sigma_color = SigmaColorOf(options);
  return so;
}

}  // namespace

MatcherOptions PmvsPassOptions(const MatcherOptions& options) {
  MatcherOptions pmvs = options;
  pmvs.mode = MatchMode::kPmvs;
  pmvs.view_angle_deg = options.pmvs_pass_view_angle_deg;
  return pmvs;
}

EngineKernels EngineKernelVariants(const MatcherOptions& options) {
  EngineKernels k;
  k.scorers.push_back(ScoreOptionsOf(options, options.window_size));
  k.refiners.push_back(RefineOptionsOf(options));
  for (const auto& [size, polish] : PolishOptionsOf(options)) {
    k.scorers.push_back(ScoreOptionsOf(options, size));
    k.refiners.push_back(polish);
  }
  if (options.mode == MatchMode::kSapmvs && options.pmvs_passes > 0) {
    const MatcherOptions pmvs = PmvsPassOptions(options);
    k.scorers.push_back(ScoreOptionsOf(pmvs, pmvs.window_size));
    k.refiners.push_back(RefineOptionsOf(pmvs));
  }
  return k;
}

PatchEngine::PatchEngine(PatchKernels& kernels, const MatchGroupData& group,
                         const MatcherOptions& options, Role role)
    : kernels_(kernels),
      group_(group),
      options_(options),
      role_(role),
      refine_options_(RefineOptionsOf(options)),
      expansion_options_(ExpansionOptionsOf(options, role)),
      polish_options_(PolishOptionsOf(options)) {
  kernels_.SetGroup(group_.ncc);
  for (size_t i = 0; i < group_.images.size(); ++i) {
    if (!group_.images[i].reference) view_only_images_.push_back(static_cast<int>(i));
  }
}

PatchEngine::~PatchEngine() { kernels_.ClearGroup(); }

std::vector<RefinedPatch> PatchEngine::RefineWith(const PatchRefinerOptions& ro,
                                                  const std::vector<NccPatch>& patches,
                                                  const std::vector<std::vector<int>>& views) {
  if (patches.empty()) return {};
  double seconds = 0;
  std::vector<RefinedPatch> out;
  {
    const std::unique_lock<std::mutex> lock = LaunchLock();
    out = kernels_.Refine(ro, patches, views, &seconds);
  }
  // Labelled by the window's side in pixels.
  const int size = static_cast<int>(std::lround((ro.patch_size - 1) * ro.sample_step)) + 1;
  double evaluations = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    evaluations += static_cast<double>(views[i].size()) * out[i].evaluations;
  }
  Count("patch_refine " + std::to_string(size) + "x" + std::to_string(size), ro.patch_size,
        static_cast<long>(patches.size()), evaluations, seconds);
  return out;
}

std::unique_lock<std::mutex> PatchEngine::LaunchLock() {
  if (kernels_.ConcurrentLaunches()) return {};
  return std::unique_lock<std::mutex>(launch_mutex_);
}

void PatchEngine::Count(const std::string& kernel, int patch_size, long items,
                        double ncc_evaluations, double seconds) {
  std::lock_guard<std::mutex> lock(count_mutex_);
  KernelTime& t = kernel_times_[kernel];
  ++t.launches;
  t.items += items;
  t.ncc_evaluations += ncc_evaluations;
  t.patch_size = patch_size;
  if (seconds > 0) {
    t.seconds += seconds;
    t.max_seconds = std::max(t.max_seconds, seconds);
  }
}

std::vector<float> PatchEngine::ScoreAt(int size, const std::vector<NccPatch>& patches,
                                        const std::vector<NccPair>& pairs) {
  if (pairs.empty()) return {};
  const NccScorerOptions so = ScoreOptionsOf(options_, size);
  double seconds = 0;
  std::vector<float> scores;
  {
    const std::unique_lock<std::mutex> lock = LaunchLock();
    scores = kernels_.Score(so, patches, pairs, &seconds);
  }
  Count("ncc_score " + std::to_string(size) + "x" + std::to_string(size), size,
        static_cast<long>(pairs.size()), static_cast<double>(pairs.size()), seconds);
  return scores;
}

std::vector<float> PatchEngine::Score(const std::vector<NccPatch>& patches,
                                      const std::vector<NccPair>& pairs) {
  return ScoreAt(options_.window_size, patches, pairs);
}

bool PatchEngine::OnParentPlane(const PatchCandidate& candidate,
                                const Eigen::Vector3d& center) const {
  if (!candidate.has_parent) return true;
  const double footprint = Footprint(group_.images[candidate.ref].camera, center);
  return std::abs(candidate.parent_normal.dot(center - candidate.parent_center)) <=
         options_.depth_tolerance * footprint;
}

std::vector<int> PatchEngine::VisibleViews(const Eigen::Vector3d& center,
                                           const Eigen::Vector3d& normal, int ref, int half) const {
  const double cos_max = std::cos(options_.view_angle_deg * M_PI / 180.0);
  auto sees = [&](int v) {
    return SeesPatch(group_.images[v].camera, center, normal, cos_max, half + 1);
  };
  std::vector<int> views, view_only;
  for (const int v : group_.images[ref].views) {
    if (sees(v)) (group_.images[v].reference ? views : view_only).push_back(v);
  }
  // Another strip's images only to bring the group's own up to
  // min_image_num, best first: at campus's 92 % forward overlap all of them
  // only added views to patches that had enough (34 % more time for 2.6
  // points of coverage), and at small's 70 % every patch took both (39 %).
  for (const int v : view_only) {
    if (static_cast<int>(views.size()) >= options_.min_image_num) break;
    views.push_back(v);
  }
  // And one to widen the angle where the group's images meet too narrowly,
  // from all its view-only images (the reference's own may fill its list):
  // at a turn, where the drone slowed, the four images of one group that
  // saw an 18 x 5 m wedge of road on the Caliterra flight met at 9.6
  // degrees at most, and PMVS2, which matches with all images, covered it.
  if (!view_only_images_.empty() && static_cast<int>(views.size()) >= options_.min_image_num - 1 &&
      !WideEnough(center, ref, views)) {
    // The list is as long as the kernels take: the least overlapping own
    // view makes room, and comes back if no image widens the angle.
    const int dropped = static_cast<int>(views.size()) >= kMaxViews - 1 ? views.back() : -1;
    if (dropped >= 0) views.pop_back();
    bool widened = false;
    for (const int w : view_only_images_) {
      if (std::find(views.begin(), views.end(), w) != views.end() || !sees(w)) continue;
      views.push_back(w);
      widened = WideEnough(center, ref, views);
      if (widened) break;
      views.pop_back();
    }
    if (!widened && dropped >= 0) views.push_back(dropped);
  }
  return views;
}

std::vector<bool> PatchEngine::CornersFit(int size, const std::vector<LargePlane>& planes,
                                          double threshold) {
  const double offset = 0.5 * (size - options_.window_size);
  std::vector<NccPatch> corners;
  std::vector<NccPair> pairs;
  std::vector<bool> ok(planes.size(), true);
  std::vector<size_t> plane_of;  // planes index of corners[i]
  for (size_t j = 0; j < planes.size(); ++j) {
    const LargePlane& pl = planes[j];
    const Camera& ref = group_.images[pl.ref].camera;
    const Eigen::Vector2d uv = ref.Project(pl.center);
    for (const auto& d : {Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1), Eigen::Vector2d(-1, 1),
                          Eigen::Vector2d(1, 1), Eigen::Vector2d(0, -1), Eigen::Vector2d(0, 1),
                          Eigen::Vector2d(-1, 0), Eigen::Vector2d(1, 0)}) {
      const Eigen::Vector3d ray = ref.Ray(uv + offset * d);
      const double s = pl.normal.dot(pl.center - ref.center()) / pl.normal.dot(ray);
      if (!std::isfinite(s) || s <= 0) {
        ok[j] = false;
        continue;
      }
      const int idx = static_cast<int>(corners.size());
      corners.push_back(MakeNccPatch(ref.center() + s * ray, pl.normal, pl.ref));
      plane_of.push_back(j);
      for (const int v : *pl.views) pairs.push_back(NccPair{idx, v});
    }
  }
  const std::vector<float> scores = ScoreAt(options_.window_size, corners, pairs);
  std::vector<double> sum(corners.size(), 0.0);
  std::vector<int> n(corners.size(), 0);
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (!std::isfinite(scores[i])) continue;  // no texture there: no evidence either way
    sum[pairs[i].patch] += scores[i];
    ++n[pairs[i].patch];
  }
  for (size_t i = 0; i < corners.size(); ++i) {
    if (n[i] > 0 && sum[i] / n[i] < threshold) ok[plane_of[i]] = false;
  }
  return ok;
}

std::vector<int> PatchEngine::WorthPolishing(
    int size, const std::vector<int>& open,
    const std::vector<std::optional<AcceptedPatch>>& results, std::vector<std::vector<int>>* views,
    std::vector<int>* rejected) {
  // A larger patch extrapolates its plane from the reference: only a view
  // at least 2 max_angle_deg from the reference pins that plane down well
  // enough. At the paper's narrow baselines (4 degrees between neighbours)
  // every view of a 4-image group is nearer, and the larger planes passed at
  // wrong depths: campus group 3 (4 images) 18.1 % within 1 GSD and 19.9 %
  // coverage with them, 30.7 % and 35.7 % without; group 1 (6 images) 27.6
  // / 32.1 % -> 37.6 / 41.5 %; `small` (25 degrees) unchanged.
  //
  // PMVS's rule before optimising, applied at each larger size with a
  // stricter bar (grow_threshold, matcher_options.h): the unpolished plane
  // must already score it in enough views, over the whole window and in each
  // border sub-window. Most large patches failed the border test after
  // polishing at threshold_before (on `small`, two thirds of those that pass
  // over the whole window at 21 x 21), and those that passed after a rescue
  // by the polish were the least accurate.
  const double bar =
      options_.grow_threshold > 0 ? options_.grow_threshold : options_.threshold_before;
  const int need = options_.min_image_num - 1;
  std::vector<NccPatch> patches;
  std::vector<NccPair> pairs;
  std::vector<int> wide;
  for (const int i : open) {
    const AcceptedPatch& a = *results[i];
    if (!WideEnough(a.center, a.ref, a.views, /*from_ref=*/true)) {
      rejected->push_back(i);
      continue;
    }
    wide.push_back(i);
    const int k = static_cast<int>(patches.size());
    patches.push_back(MakeNccPatch(a.center, a.normal, a.ref));
    for (const int v : a.views) pairs.push_back(NccPair{k, v});
  }
  const std::vector<float> scores = ScoreAt(size, patches, pairs);
  std::vector<int> scored;
  std::vector<std::vector<int>> scored_views;
  size_t pair_index = 0;
  for (const int i : wide) {
    std::vector<int> kept;
    for (const int v : results[i]->views) {
      const float x = scores[pair_index++];
      if (std::isfinite(x) && x >= bar) kept.push_back(v);
    }
    if (static_cast<int>(kept.size()) < need) {
      rejected->push_back(i);
      continue;
    }
    scored.push_back(i);
    scored_views.push_back(std::move(kept));
  }
  std::vector<LargePlane> planes;
  for (size_t j = 0; j < scored.size(); ++j) {
    const AcceptedPatch& a = *results[scored[j]];
    planes.push_back(LargePlane{a.center, a.normal, a.ref, &scored_views[j]});
  }
  const std::vector<bool> fit = CornersFit(size, planes, bar);
  std::vector<int> worth;
  views->clear();
  for (size_t j = 0; j < scored.size(); ++j) {
    if (!fit[j]) {
      rejected->push_back(scored[j]);
      continue;
    }
    worth.push_back(scored[j]);
    views->push_back(std::move(scored_views[j]));
  }
  return worth;
}

bool PatchEngine::WideEnough(const Eigen::Vector3d& x, int ref, const std::vector<int>& views,
                             bool from_ref) const {
  // PMVS2's checkAngles: some pair of the patch's images, the reference
  // included, must meet at x at more than max_angle_deg (else the depth is
  // barely constrained) and less than view_angle_deg (else the two cannot
  // both see one plane well). from_ref (the larger adaptive sizes, see
  // WorthPolishing): a pair of the reference and a view, at more than twice
  // max_angle_deg. Narrower views still take part in the scores:
  // in a strip at the paper's 88 % overlap every neighbour is narrower than
  // 10 degrees, but the neighbours on either side of the reference are not
  // narrow to each other.
  const double lo = std::cos((from_ref ? 2 : 1) * options_.max_angle_deg * M_PI / 180.0);
  const double hi = std::cos(options_.view_angle_deg * M_PI / 180.0);
  std::vector<Eigen::Vector3d> rays = {(group_.images[ref].camera.center() - x).normalized()};
  for (const int v : views) rays.push_back((group_.images[v].camera.center() - x).normalized());
  for (size_t a = 0; a < (from_ref ? 1 : rays.size()); ++a) {
    for (size_t b = a + 1; b < rays.size(); ++b) {
      const double c = rays[a].dot(rays[b]);
      if (c < lo && c > hi) return true;
    }
  }
  return false;
}

std::vector<std::optional<AcceptedPatch>> PatchEngine::Evaluate(
    const std::vector<PatchCandidate>& candidates) {
  // Below this many candidates a half's kernels are too short to hide the
  // other half's host steps behind.
  constexpr size_t kMinHalf = 256;
  if (candidates.size() < 2 * kMinHalf || HostThreadCount() < 2) return EvaluateBatch(candidates);
  const auto mid = candidates.begin() + static_cast<long>(candidates.size() / 2);
  const std::vector<PatchCandidate> halves[2] = {{candidates.begin(), mid},
                                                 {mid, candidates.end()}};
  std::vector<std::optional<AcceptedPatch>> results[2];
  ParallelFor(
      2, [&](long h) { results[h] = EvaluateBatch(halves[h]); }, 1);
  results[0].insert(results[0].end(), std::make_move_iterator(results[1].begin()),
                    std::make_move_iterator(results[1].end()));
  return std::move(results[0]);
}

std::vector<std::optional<AcceptedPatch>> PatchEngine::EvaluateBatch(
    const std::vector<PatchCandidate>& candidates) {
  const int need = options_.min_image_num - 1;
  const int half = options_.window_size / 2;
  const double cos_max = std::cos(options_.view_angle_deg * M_PI / 180.0);
  std::vector<std::optional<AcceptedPatch>> results(candidates.size());

  // 1. Visible views and the score before optimisation.
  std::vector<NccPatch> patches;
  std::vector<int> patch_of;  // candidate index of patches[k]
  std::vector<std::vector<int>> visible;
  std::vector<NccPair> pairs;
  for (size_t i = 0; i < candidates.size(); ++i) {
    const PatchCandidate& c = candidates[i];
    const Camera& ref = group_.images[c.ref].camera;
    Eigen::Vector3d n = c.normal.normalized();
    const Eigen::Vector3d to_ref = (ref.center() - c.center).normalized();
    if (n.dot(to_ref) < 0) n = -n;
    if (!n.allFinite() || n.dot(to_ref) < cos_max) continue;
    if (!(ref.Depth(c.center) > 0) || !ref.InImage(ref.Project(c.center), half + 1)) continue;
    std::vector<int> views = VisibleViews(c.center, n, c.ref, half);
    if (static_cast<int>(views.size()) < need) continue;
    const int k = static_cast<int>(patches.size());
    patches.push_back(MakeNccPatch(c.center, n, c.ref));
    patch_of.push_back(static_cast<int>(i));
    for (const int v : views) pairs.push_back(NccPair{k, v});
    visible.push_back(std::move(views));
  }
  const std::vector<float> before = ScoreAt(options_.window_size, patches, pairs);

  // 2. Refine with the views that pass threshold_before.
  std::vector<NccPatch> to_refine;
  std::vector<std::vector<int>> refine_views;
  std::vector<int> refine_of;
  std::vector<float> kept_scores;
  size_t pair_index = 0;
  for (size_t k = 0; k < patches.size(); ++k) {
    std::vector<int> kept;
    kept_scores.clear();
    for (const int v : visible[k]) {
      const float s = before[pair_index++];
      if (std::isfinite(s) && s >= options_.threshold_before) {
        kept.push_back(v);
        kept_scores.push_back(s);
      }
    }
    if (static_cast<int>(kept.size()) < need) continue;
    if (!WideEnough(candidates[patch_of[k]].center, candidates[patch_of[k]].ref, kept)) continue;
    to_refine.push_back(patches[k]);
    // A one-cell candidate whose parent's plane already scores
    // kOneCellDepthOnlyScore in as many views as acceptance asks for is
    // explained by that plane: its depth is searched, its normal kept.
    if (role_ == Role::kOneCellPass && candidates[patch_of[k]].has_parent) {
      std::nth_element(kept_scores.begin(), kept_scores.begin() + (need - 1), kept_scores.end(),
                       std::greater<float>());
      if (kept_scores[need - 1] >= kOneCellDepthOnlyScore) to_refine.back().directions = 2;
    }
    refine_views.push_back(std::move(kept));
    refine_of.push_back(patch_of[k]);
  }
  // Seeds and expansions come in separate batches (Propagator).
  const bool expansion = std::all_of(candidates.begin(), candidates.end(),
                                     [](const PatchCandidate& c) { return c.has_parent; }) &&
                         !candidates.empty();
  const std::vector<RefinedPatch> refined =
      RefineWith(expansion ? expansion_options_ : refine_options_, to_refine, refine_views);

  // 3. Accept on the views that pass threshold after optimisation.
  std::vector<int> accepted_index;
  for (size_t k = 0; k < refined.size(); ++k) {
    const RefinedPatch& r = refined[k];
    if (!std::isfinite(r.score)) continue;
    AcceptedPatch a;
    a.center = Eigen::Vector3d(r.patch.center.s[0], r.patch.center.s[1], r.patch.center.s[2]);
    a.normal = Eigen::Vector3d(r.patch.normal.s[0], r.patch.normal.s[1], r.patch.normal.s[2]);
    a.ref = r.patch.reference;
    // The refinement keeps the normal within view_angle_deg of the
    // reference, in float32: a normal on the cone's rim may read a hair
    // outside it in double, and is kept.
    if (!Faces(group_.images[a.ref].camera, a.center, a.normal, cos_max - kRimSlack)) continue;
    if (!OnParentPlane(candidates[refine_of[k]], a.center)) continue;
    double sum = 0;
    for (size_t v = 0; v < refine_views[k].size(); ++v) {
      if (r.view_scores[v] >= options_.threshold &&
          Faces(group_.images[refine_views[k][v]].camera, a.center, a.normal, cos_max)) {
        a.views.push_back(refine_views[k][v]);
        sum += r.view_scores[v];
      }
    }
    if (static_cast<int>(a.views.size()) < need ||
        !WideEnough(a.center, a.ref, a.views, /*from_ref=*/role_ == Role::kOneCellPass)) {
      continue;
    }
    a.score = static_cast<float>(sum / a.views.size());
    a.size = options_.window_size;
    results[refine_of[k]] = std::move(a);
    accepted_index.push_back(refine_of[k]);
  }
  if (options_.mode != MatchMode::kSapmvs) return results;

  // 4. Self-adaptive size: the largest patch that is still photo-consistent.
  std::vector<int> open = accepted_index;
  for (const int size : options_.adaptive_sizes) {
    if (size <= options_.window_size || open.empty()) break;
    std::vector<std::vector<int>> q;
    std::vector<int> still_open;
    open = WorthPolishing(size, open, results, &q, &still_open);
    std::vector<NccPatch> p;
    for (const int i : open) {
      p.push_back(MakeNccPatch(results[i]->center, results[i]->normal, results[i]->ref));
    }
    const std::vector<RefinedPatch> polished = RefineWith(polish_options_.at(size), p, q);
    // Patches that pass at this size, before the corner test.
    struct Pass {
      size_t k;
      Eigen::Vector3d c, n;
      std::vector<int> views;
      double score;
    };
    std::vector<Pass> passing;
    for (size_t k = 0; k < open.size(); ++k) {
      const AcceptedPatch& a = *results[open[k]];
      const RefinedPatch& r = polished[k];
      const Eigen::Vector3d c(r.patch.center.s[0], r.patch.center.s[1], r.patch.center.s[2]);
      const Eigen::Vector3d n(r.patch.normal.s[0], r.patch.normal.s[1], r.patch.normal.s[2]);
      std::vector<int> pass;
      double sum = 0;
      const bool faces_ref = Faces(group_.images[a.ref].camera, c, n, cos_max) &&
                             OnParentPlane(candidates[open[k]], c);
      for (size_t v = 0; v < q[k].size() && faces_ref; ++v) {
        const float x = r.view_scores[v];
        if (std::isfinite(x) && x >= options_.threshold &&
            Faces(group_.images[q[k][v]].camera, c, n, cos_max)) {
          pass.push_back(q[k][v]);
          sum += x;
        }
      }
      if (std::isfinite(r.score) && static_cast<int>(pass.size()) >= need &&
          WideEnough(c, a.ref, pass, /*from_ref=*/true)) {
        const double mean = sum / static_cast<double>(pass.size());
        passing.push_back(Pass{k, c, n, std::move(pass), mean});
      } else {
        still_open.push_back(open[k]);
      }
    }
    // The plane must fit in each corner of the large patch too: a patch
    // straddling a roof edge or a break of slope scores well over its whole
    // window (the fitting part dominates) but not in the corner that lies on
    // the other surface.
    std::vector<LargePlane> planes;
    for (const Pass& ps : passing) {
      planes.push_back(LargePlane{ps.c, ps.n, results[open[ps.k]]->ref, &ps.views});
    }
    const std::vector<bool> corner_ok = CornersFit(size, planes, options_.threshold);
    for (size_t j = 0; j < passing.size(); ++j) {
      Pass& ps = passing[j];
      if (!corner_ok[j]) {
        still_open.push_back(open[ps.k]);
        continue;
      }
      AcceptedPatch& a = *results[open[ps.k]];
      a.center = ps.c;
      a.normal = ps.n;
      a.size = size;
      a.score = static_cast<float>(ps.score);
      a.views = std::move(ps.views);
    }
    open = std::move(still_open);
  }
  return results;
}

}  // namespace sapmvs

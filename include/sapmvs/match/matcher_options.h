#pragma once
// The matcher's options (MatcherOptions) and their description, apart from
// the matcher (match_group.h) so that the planner, the checkpoints and the CLI
// can take them without the matcher's API.
#include <string>
#include <vector>

#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/option_spec.h"

namespace sapmvs {

enum class MatchMode { kSapmvs, kPmvs };
std::string ToString(MatchMode mode);
// Throws Error naming `text` unless it is "sapmvs" or "pmvs".
MatchMode ParseMatchMode(const std::string& text);
inline void ParseOptionValue(const std::string& text, MatchMode* mode) {
  *mode = ParseMatchMode(text);
}

struct MatcherOptions {
  MatchMode mode = MatchMode::kSapmvs;
  // Pyramid level the group is matched at: 0 = full resolution, 1 = half
  // (PMVS2's `level`), ... Each level halves both image sides.
  int level = 1;
  // Side of an image cell in pixels at `level` (PMVS2's `csize`): the grid
  // that says which parts of an image are already covered.
  int cell_size = 2;
  // Mean NCC over the accepted views a patch needs after optimisation
  // (PMVS2's `threshold`), and the per-view NCC a view needs to count.
  double threshold = 0.7;
  // Per-view NCC a view needs before optimisation to take part in it.
  double threshold_before = 0.4;
  // Images (reference included) a patch must be photo-consistent in
  // (PMVS2's `minImageNum`), 2 to kMaxViews.
  int min_image_num = 3;
  // PMVS2's `maxAngle`, degrees: a patch is accepted only if some pair of
  // the images it is matched in (the reference included) meets at it at more
  // than this (and less than view_angle_deg), so that its depth is
  // constrained. Each view on its own may be narrower: at the paper's 88 %
  // forward overlap every neighbour of an image is (4 degrees apart).
  double max_angle_deg = 10.0;
  // Largest angle, degrees, between a patch normal and the direction to an
  // image for that image to be a visible view of the patch. The refinement
  // searches normals within this angle of the reference ray, at most 89
  // degrees (PatchRefinerOptions::max_angle_deg's limit), so values between 89
  // and 90 refine as 89.
  double view_angle_deg = 60.0;
  // Side of the matching window (PMVS2's `wsize`), pixels, odd: the patch
  // refined by the device, and the smallest adaptive patch.
  int window_size = 7;
  // Self-adaptive patch sides tried in order, pixels, odd, decreasing, each
  // <= kMaxPatchSize; the last must equal window_size (sapmvs mode).
  std::vector<int> adaptive_sizes = {21, 15, 11, 7};
  // sapmvs: largest spacing, in pixels, of the samples that score a window
  // larger than window_size. A side L is sampled on the fewest odd grid that
  // keeps its spacing at most this, L still spanned end to end: at 2, 21 px
  // by 11 x 11 samples 2 px apart, 15 by 9 x 9 (1.75 px), 11 by 7 x 7
  // (1.67 px), a quarter to two fifths of the samples. A speed knob, not the
  // default: at 2 the device time fell 19 % on `small` and 17 % on city, but
  // city lost 2.4 points within 1 GSD and 1.4 of coverage (sparse samples
  // alias fine texture, and the polish settles on other planes). 1 = every
  // pixel, as the paper.
  double adaptive_sample_step = 1.0;
  // sapmvs: a patch is polished at a larger adaptive size only when its
  // plane, as refined at the smaller one, already scores at least this at
  // the larger size in enough views, over the window and in each corner
  // sub-window: the plane must be shown to hold over the larger window
  // before the larger window may write points. With PMVS's
  // threshold_before (0.4, grow_threshold 0 here) most
  // polishes failed and the large patches that passed were the least
  // accurate. One group, one run each, 0.4 -> 0.9: `small` 96.7 -> 97.6 %
  // within 1 GSD, coverage 74.4 -> 75.7 %, time -19 %; `city` 90.7 -> 94.7 %,
  // 65.9 -> 69.1 %, -18 %; campus (12 groups) 56.8 -> 59.6 %, 49.4 ->
  // 51.1 %; Herz-Jesu-P8 52.6 -> 42.0 s. 0.7 and 0.8 lay between; 0.95 and
  // no larger size at all (adaptive_sizes 7) covered less.
  double grow_threshold = 0.9;
  // sapmvs: NCC sample weights. Each sample of a window counts
  // exp(-d^2 / 2 s^2), d its difference from the window's centre sample in
  // the reference image and s this many standard deviations of the 3 x 3
  // samples around the centre, so that a window straddling a wall, a roof
  // edge or a crown scores the surface under its centre rather than failing
  // or settling on a depth between the two. Relative, so one value suits
  // scans and renderings of any contrast (from a spread of at least
  // kNccWeightMinSpread: weak texture scores as plain NCC); smaller is
  // sharper at edges but noisier on weak texture (on `small` with 4
  // features per block, 1.5: 73.0 % coverage; 3: 72.4 %; NGI keeps 87 % of
  // its points at 3, 76 % at 2). 0 = plain NCC; pmvs mode always scores
  // plain NCC, as PMVS does.
  double ncc_sigma_color = 3.0;
  // sapmvs: a pixel of an accepted window gets a point only where the
  // weighted NCC gave it at least this weight (ncc_sigma_color), so that a
  // plane is not written across the roof edge or crown rim that the weights
  // discounted. 0.3 keeps grey levels within 1.55 s of the centre's: on
  // `small` (one group, no refit) 91.9 -> 94.3 % within 1 GSD at 75.6 %
  // coverage (75.9 % with every pixel). 0 = every pixel the flood fill
  // reaches, as the paper.
  double emit_min_weight = 0.3;
  // sapmvs: each patch's plane is fitted to the centres of this many nearest
  // patches (plane_refit.h) after each expansion, and its points moved onto
  // it; a patch that fewer than 3 of them confirm keeps only the points
  // within 1 pixel of its centre. 0 = off: every point stays on its refined
  // plane, whose normal a small window hardly constrains.
  int refit_neighbours = 16;
  // sapmvs: a neighbour's centre confirms a patch's plane when it lies within
  // this many footprints of it, which keeps the patches of a roof out of the
  // ground's fit and those of the ground out of the roof's. Tighter is more
  // accurate and cuts more patches back: `compare_modes`, one group, within
  // 1 GSD / coverage, `small` 96.1 / 75.2 % at 1 and 96.8 / 74.4 % at 0.7;
  // `city` 89.4 / 67.3 % and 90.7 / 65.7 %; city against its LiDAR (3
  // groups) 93.4-93.9 % and 94.4 % within 1 m.
  double refit_tolerance = 0.7;
  // sapmvs: after each refit, propagate again into the pixels of the patches
  // it cut back, from their centres. More coverage for more time and a little
  // accuracy: `compare_modes`, one group, with refit_tolerance 0.5, `small`
  // 95.7 % within 1 GSD and 79.8 % coverage in 10.4 s (default: 96.8 %,
  // 74.4 %, 7.7 s); `city` 88.6 %, 72.4 %, 26.3 s (90.7 %, 65.7 %, 16.6 s).
  bool refill_cut = false;
  // Features kept per detector per 32 x 32 pixel block (PMVS: 4). 8 seeds
  // the roofs that 4 left without a single right seed: on `small` coverage
  // 72.4 -> 75.5 % (sapmvs) and 63.8 -> 64.9 % (pmvs) at the same accuracy
  // and time; NGI gains points in both modes.
  int features_per_block = 8;
  // sapmvs: of those, the strongest this many per detector and block seed
  // the first waves; the others are matched and tried only where those waves
  // left their cell empty (0 = all seed at once, as PMVS; pmvs mode always).
  // Most of the second half fall on ground the first half's patches grow
  // over anyway, and the seeds were a fifth of a run. Against all at once
  // (versus_pmvs2 --pmvs2-cloud, the same PMVS2 clouds, level 1, 2 cores):
  // Herz-Jesu-P8's seeds 5.9 -> 3.7 s, seeds tried 205,896 -> 141,944, wall
  // 28.0 -> 25.5 s, PMVS2's points within 2 GSD of ours 85.8 % in both;
  // the Caliterra flight (18 groups) 67.7 -> 61.2 s, 82.3 -> 82.1 %, ground
  // covered 96.7 -> 96.5 %; `small` and `city` within 1 GSD of the truth
  // 91.9 -> 92.0 % and 89.7 % in both, coverage 79.5 -> 79.3 % and 74.6 ->
  // 74.4 %. Keeping only 4 per block was as fast but lost `small`'s
  // accuracy (91.6 %), and lets a surface no strong feature seeds go
  // unmatched.
  int first_features_per_block = 4;
  // Candidate matches lie within this many pixels of the epipolar line.
  double epipolar_distance = 2.0;
  // Candidates tried per feature, best ordered first.
  int candidates_per_feature = 4;
  // Canny thresholds on 8-bit grey for edge points; edge pixels matched
  // along epipolar lines become propagation barriers (sapmvs mode).
  double canny_low = 40;
  double canny_high = 120;
  // The paper's edge barriers, off by default: matching the edges took 10-20 %
  // of sapmvs's time on `small`, `city` and Herz-Jesu-P8 and changed none of
  // their clouds measurably (docs/method.md 3.7),
  // since emit_min_weight already stops a window at the edges it straddles.
  bool use_edges = false;
  // Expand-then-filter passes (PMVS: n = 3). Each pass after the first frees
  // the cells of the points the filter removed and grows the surviving
  // patches into them again.
  int expand_iterations = 3;
  // sapmvs: the last this many of those passes grow as PMVS does: from every
  // kept point into the 4 empty cells beside its own, each candidate a patch
  // of one cell, scored with plain NCC at window_size (no polish, no colour
  // weights), emitting its centre and not refit. They cover the rims of the
  // holes the adaptive patches left, where a window straddled a depth edge
  // or the refit cut a patch back. One such pass in place of the third
  // adaptive one, against PMVS2's cloud of the same run (`versus_pmvs2
  // --pmvs2-cloud`): PMVS2's points covered within 2 GSD 69.4 -> 75.2 % on
  // Herz-Jesu-P8, 84.1 -> 85.5 % on `small`, 80.5 -> 82.4 % on `city`, at
  // the same accuracy against the truth (within 1 GSD 97.7 -> 97.8 %,
  // 93.7 -> 94.0 %), for 0-19 % more time. Their patches need a view at
  // least 2 max_angle_deg from the reference, and the filter does not judge
  // their planes (PatchEngine::Role::kOneCellPass, PatchClasses), which
  // covers walls: 87.4 -> 90.4 % on `small`, 83.8 -> 87.5 % on `city`.
  // Their rims are offered in the patches' wide views too, as PMVS2 expands
  // in every image a patch is seen in (Propagator::OfferInViews): 92.3 ->
  // 93.4 %, 89.6 -> 90.1 %, Herz-Jesu-P8 82.4 -> 84.0 %, for 8-14 % more
  // time; at every wave, not only from the pass's start (Expand): 93.0 ->
  // 94.0 %, 90.1 -> 91.1 %, 84.0 -> 86.5 % (of PMVS2's right points on
  // walls 67.7 -> 72.6 % and 77.3 -> 79.1 %), within 2 GSD of the truth in
  // 3D 99.2 -> 98.9 % and 99.3 -> 99.2 %, for 10-18 % more time. 0 = every
  // pass adaptive.
  int pmvs_passes = 1;
  // sapmvs: view_angle_deg for those passes' one-cell patches. A patch's
  // plane there only has to hold over its window, and only its centre is
  // emitted, where an adaptive patch's plane is extrapolated over up to
  // 21 x 21 pixels and refit from its neighbours; so ground seen at grazing
  // angles may be matched there. With 80 against 60, against PMVS2's clouds
  // of the same runs: Herz-Jesu-P8's forecourt 14.7 -> 50.5 % covered, the
  // whole 75.2 -> 79.4 %, ours within 2 GSD of PMVS2's 92.5 -> 92.0 %;
  // `small` 85.5 -> 86.0 % at 97.8 -> 97.6 % within 1 GSD, `city` 82.4 ->
  // 82.7 % at 94.0 %, `campus` 72.2 -> 72.1 % within 0.5 m; 85 covered
  // 80.9 % and left 91.0 % of ours near PMVS2's.
  double pmvs_pass_view_angle_deg = 80.0;
  // sapmvs: the plane tolerance of the filter's neighbourhood test for a
  // pmvs pass's one-cell patch whose depth its views resolve to within it:
  // where a pixel of disparity in its best-placed view moves its centre at
  // most this many footprints of its reference along its reference's ray
  // (a view 30 degrees off the reference's ray at 2, if the footprints are
  // alike; DisparityDepth). Such a patch lies where its views put it, and
  // its 16 nearest points may not span one plane: on a wall under 7 pixels
  // wide, their plane is half the roof's. PMVS2 judges its patches by a
  // quadric through their neighbours, within a mean 2 footprints (its
  // `quad`). Against PMVS2's clouds of the same runs (versus_pmvs2
  // --pmvs2-cloud): PMVS2's points covered within 2 GSD `small` 90.4 ->
  // 92.3 %, `city` 87.5 -> 89.6 %, Herz-Jesu-P8 81.2 -> 82.4 %; within 2
  // GSD of the truth in 3D 99.6 -> 99.3 %, 99.5 -> 99.3 % (the points added
  // 85 % and 90 %). On `campus` (50 m between strips at 700 m, views
  // meeting at 20-30 degrees) none qualify: 2 footprints for every one-cell
  // patch took it from 72.9 to 71.9 % within 0.5 m. 0 = their tolerance is
  // the others'.
  double pmvs_pass_plane_tolerance = 2.0;
  // Most candidate patches one device launch takes.
  int max_wave = 16384;
  // Waves stop after this many (0 = until the front is empty).
  int max_waves = 0;
  // Score fence, in robust standard deviations (1.4826 x MAD): points of a
  // patch scoring further than this below the median score of the first
  // expansion's points go (0 = off). Most points are right, so their scores
  // show what a right match scores on these images (their noise and
  // texture): about 0.98 on the simulator's, 0.89 on NGI's scans; a fixed
  // `threshold` (0.7, the floor) cannot be both. In sapmvs mode the pmvs
  // passes' one-cell patches meet a fence of the same width from the scores
  // of their own first pass's points: plain NCC over one window_size window
  // scores on another scale than the adaptive patches' weighted NCC (on
  // `small` medians 0.92 and 0.985), and the adaptive fence (0.95) cut 64 %
  // of their points, 79 % of those within 2 GSD of the truth, walls among them.
  double score_fence = 3.0;
  // Depth agreement tolerance, in pixel footprints: in the visibility filter
  // along the point's plane's slope (face-on footprints over the cosine of
  // the angle to the line of sight), in propagation and the edge barriers
  // off a patch's plane.
  double depth_tolerance = 3.0;
  // Neighbourhood test: neighbours within this many footprints of a point,
  // along its plane's slope.
  double neighbour_radius = 4.0;
  // A point needs this many neighbours, and must lie within the plane
  // tolerance of the plane they fit; a patch's plane must pass within it of
  // most neighbouring points of other patches. The tolerance is
  // plane_sigmas robust standard deviations of the distances between
  // neighbouring patches (how noisy this group's depths are), and at least
  // plane_tolerance footprints. Half a footprint (one full-resolution GSD at
  // level 1): a fixed 1.5 let a quarter of the sapmvs points on
  // `simulate --preset small` stray beyond 1 GSD.
  int min_neighbours = 4;
  double plane_tolerance = 0.5;
  double plane_sigmas = 1.5;
  // Clusters (points linked within neighbour_radius) smaller than this are
  // removed.
  int min_cluster_size = 30;
  // sapmvs: the filters of the first this many passes test the score floor
  // and visibility only; the neighbourhood, plane-support and cluster tests,
  // and the neighbour table that is most of a filter's time, wait for a
  // later pass (the last pass's filter always runs every test; 0 = every
  // filter does, as PMVS; pmvs mode always). The first pass's neighbourhood
  // failures only keep their cells from the second adaptive pass, whose
  // filter then removes them: 1 against 0 (versus_pmvs2 --pmvs2-cloud, the
  // same PMVS2 clouds, level 1, 2 cores): Herz-Jesu-P8 26.2 -> 24.2 s
  // (filter 5.4 -> 4.2 s), PMVS2's points within 2 GSD of ours 85.8 ->
  // 86.1 %, ground covered 84.3 % in both, local noise 4.5 mm in both;
  // `city` 5.2 -> 4.7 s, 89.8 -> 90.0 %, within 1 GSD of the truth 89.7 ->
  // 89.4 %; `small` 2.7 -> 2.5 s, 93.6 -> 93.8 %, 92.0 -> 91.9 %; the
  // Caliterra flight (18 groups) 64.5 -> 62.1 s, 82.1 -> 82.5 %, ground
  // covered 96.5 -> 96.9 %, local noise 1.73 -> 1.80 cm. Testing
  // visibility only in the second pass's filter as well (2) lost 1.6
  // points of Herz-Jesu-P8's and 1.2 of `city`'s PMVS2 points, and in the
  // second pass's alone 1.0 and 1.1: its outliers then hold the cells the
  // one-cell pass grows into. Off by default: on `campus` (strips 50 m apart
  // at 700 m, views meeting at 20-30 degrees) 1 lost 1.2 points of the
  // points within 1 m of the truth (86.6 against 87.8 %) and 4.1 % of the
  // filled cells, for 6 % less time, and planned as narrow strips
  // (`--strategy strip --max-images 6`) 1.9 points (85.3 against 87.2 %)
  // and 3.3 % of the cells: there a first-pass outlier grows a patch that
  // the later filters no longer tell from the surface.
  int visibility_only_filters = 0;
  // Show progress on a terminal.
  bool progress = true;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
  // The first failing condition as "what was expected (name = value)", or ""
  // when the options are valid; for callers that report errors themselves.
  std::string Problem() const;
};

// The description of every field (option_spec.h): flag, unit, range, help.
// Fields without a flag are not options of the command line.
template <class F>
void VisitFields(MatcherOptions& o, F&& f) {
  const char* s = "Matching";
  f(Field(o.mode, "mode").Flag("--mode").In(s).Help("sapmvs (self-adaptive patch) or pmvs"));
  f(Field(o.level, "level")
        .Flag("--level")
        .In(s)
        .Range(Between(0, kMaxLevel))
        .Help("Pyramid level: 0 full resolution, 1 half, ..."));
  f(Field(o.cell_size, "cell_size")
        .Flag("--csize")
        .In(s)
        .Unit("px at the level")
        .Range(Between(1, 16))
        .Help("Cell size, pixels at the level"));
  f(Field(o.threshold, "threshold")
        .Flag("--threshold")
        .In(s)
        .Unit("NCC")
        .Range(Interval(-1, 1, true, false))
        .Help("NCC a view needs after optimisation"));
  f(Field(o.threshold_before, "threshold_before")
        .Flag("--threshold-before")
        .In(s)
        .Unit("NCC")
        .Range(Interval(-1, 1, true, false))
        .Rule("<= threshold")
        .Help("NCC a view needs before optimisation"));
  f(Field(o.min_image_num, "min_image_num")
        .Flag("--min-image-num")
        .In(s)
        .Unit("images")
        .Range(Between(2, kMaxViews))
        .Help("Images a patch must be photo-consistent in"));
  f(Field(o.max_angle_deg, "max_angle_deg")
        .Flag("--max-angle")
        .In(s)
        .Unit("deg")
        .Range(Interval(0, 90, false, true))
        .Help("PMVS2's maxAngle: some pair of a patch's images must meet at more than this, "
              "degrees"));
  f(Field(o.view_angle_deg, "view_angle_deg")
        .Flag("--view-angle")
        .In(s)
        .Unit("deg")
        .Range(Interval(0, 90, true, true))
        .Help("Largest angle of a view to a patch normal, degrees"));
  f(Field(o.window_size, "window_size")
        .Flag("--wsize")
        .In(s)
        .Unit("px")
        .Range(OddBetween(3, kMaxPatchSize))
        .Help("Matching window, pixels (odd)"));
  f(Field(o.adaptive_sizes, "adaptive_sizes")
        .Flag("--adaptive-sizes")
        .In(s)
        .Unit("px")
        .Style(FlagStyle::kList)
        .Range(OddBetween(3, kMaxPatchSize))
        .Rule("decreasing, the last = window_size (sapmvs mode)")
        .Help("sapmvs patch sides, largest first"));
  f(Field(o.adaptive_sample_step, "adaptive_sample_step")
        .Flag("--adaptive-sample-step")
        .In(s)
        .Unit("px")
        .Range(Between(1, kMaxSampleStep))
        .AsVersion1(1.0)
        .Help("sapmvs: largest spacing of the samples scoring a window larger than --wsize (1 = "
              "every pixel)"));
  f(Field(o.grow_threshold, "grow_threshold")
        .Flag("--grow-threshold")
        .In(s)
        .Range(Between(0, 1))
        .AsVersion1(0.0)
        .Help("sapmvs: a patch is tried at a larger size only when its plane already scores "
              "this there, over the window and in each corner (0 = --threshold-before)"));
  f(Field(o.ncc_sigma_color, "ncc_sigma_color")
        .Flag("--ncc-sigma-color")
        .In(s)
        .Unit("SDs")
        .Range(AtLeast(0))
        .Help("sapmvs: NCC sample weights, in SDs of the texture at the window's centre (0 = "
              "plain NCC)"));
  f(Field(o.emit_min_weight, "emit_min_weight")
        .Flag("--emit-min-weight")
        .In(s)
        .Range(Between(0, 1))
        .AsVersion1(0.0)
        .Help("sapmvs: a window pixel gets a point only with at least this NCC sample weight (0 "
              "= every pixel)"));
  f(Field(o.refit_neighbours, "refit_neighbours")
        .Flag("--refit-neighbours")
        .In(s)
        .Unit("patches")
        .Range(Between(0, 64))
        .AsVersion1(0)
        .Help("sapmvs: fit each patch plane to this many neighbouring centres (0 = off)"));
  f(Field(o.refit_tolerance, "refit_tolerance")
        .Flag("--refit-tolerance")
        .In(s)
        .Unit("footprints")
        .Range(Above(0))
        .UnusedWhen(o.refit_neighbours == 0)
        .Help("sapmvs: a neighbouring centre within this of a patch plane confirms it"));
  f(Field(o.refill_cut, "refill_cut")
        .Flag("--refill-cut")
        .In(s)
        .AsVersion1(false)
        .UnusedWhen(o.refit_neighbours == 0)
        .Help("sapmvs: propagate again into the pixels the plane refit cut (more coverage, "
              "more time)"));
  s = "Seeds and edges";
  f(Field(o.features_per_block, "features_per_block")
        .Flag("--features-per-block")
        .In(s)
        .Range(AtLeast(1))
        .Help("Features per detector per 32x32 block"));
  f(Field(o.first_features_per_block, "first_features_per_block")
        .Flag("--first-features-per-block")
        .In(s)
        .Range(AtLeast(0))
        .AsVersion1(0)
        .UnusedWhen(o.mode == MatchMode::kPmvs)
        .Help("sapmvs: of those, the strongest this many seed first, the others only cells the "
              "first waves left empty (0 = all at once)"));
  f(Field(o.epipolar_distance, "epipolar_distance")
        .Flag("--epipolar-distance")
        .In(s)
        .Unit("px")
        .Range(Above(0))
        .Help("Seed candidates: pixels from the epipolar line"));
  f(Field(o.candidates_per_feature, "candidates_per_feature")
        .Flag("--candidates")
        .In(s)
        .Range(AtLeast(1))
        .Help("Seed candidates tried per feature"));
  f(Field(o.canny_low, "canny_low")
        .Flag("--canny-low")
        .In(s)
        .Unit("grey levels")
        .Range(AtLeast(0))
        .Rule("<= canny_high")
        .Help("sapmvs: Canny's low threshold on 8-bit grey, for edge points"));
  f(Field(o.canny_high, "canny_high")
        .Flag("--canny-high")
        .In(s)
        .Unit("grey levels")
        .Range(Above(0))
        .Help("sapmvs: Canny's high threshold on 8-bit grey, for edge points"));
  f(Field(o.use_edges, "use_edges")
        .Flag("--edges")
        .In(s)
        .Help("sapmvs: match edges and stop windows at them (the paper's barriers; slower, "
              "no measured gain)"));
  s = "Propagation";
  f(Field(o.max_wave, "max_wave")
        .Flag("--max-wave")
        .In(s)
        .Unit("patches")
        .Range(AtLeast(1))
        .Help("Most candidates per device launch"));
  f(Field(o.max_waves, "max_waves")
        .Flag("--max-waves")
        .In(s)
        .Range(AtLeast(0))
        .Help("Stop after this many waves (0 = none)"));
  f(Field(o.expand_iterations, "expand_iterations")
        .Flag("--expand-iterations")
        .In(s)
        .Range(Between(1, 10))
        .Help("Expand-then-filter passes (PMVS: 3)"));
  f(Field(o.pmvs_passes, "pmvs_passes")
        .Flag("--pmvs-passes")
        .In(s)
        .Range(Between(0, 10))
        .AsVersion1(0)
        .UnusedWhen(o.mode == MatchMode::kPmvs)
        .Help("sapmvs: of the passes, the last grow one-cell patches as PMVS does, into what "
              "the adaptive patches left (0 = none)"));
  f(Field(o.pmvs_pass_view_angle_deg, "pmvs_pass_view_angle_deg")
        .Flag("--pmvs-pass-view-angle")
        .In(s)
        .Unit("deg")
        .Range(Interval(0, 90, true, true))
        .UnusedWhen(o.mode == MatchMode::kPmvs || o.pmvs_passes == 0)
        .Help("sapmvs: --view-angle of the pmvs passes' one-cell patches, degrees"));
  s = "Filter";
  f(Field(o.pmvs_pass_plane_tolerance, "pmvs_pass_plane_tolerance")
        .Flag("--pmvs-pass-plane-tolerance")
        .In(s)
        .Unit("footprints")
        .Range(AtLeast(0))
        .UnusedWhen(o.mode == MatchMode::kPmvs || o.pmvs_passes == 0)
        .Help("Filter: plane tolerance of a pmvs pass's one-cell patch whose views resolve its "
              "depth to within it, footprints (0 = --plane-tolerance's)"));
  f(Field(o.visibility_only_filters, "visibility_only_filters")
        .Flag("--visibility-only-filters")
        .In(s)
        .Range(Between(0, 9))
        .AsVersion1(0)
        .UnusedWhen(o.mode == MatchMode::kPmvs)
        .Help("Filter (sapmvs): the first this many passes' filters test scores and visibility "
              "only, the last always all (0 = every filter tests all)"));
  f(Field(o.score_fence, "score_fence")
        .Flag("--score-fence")
        .In(s)
        .Unit("robust SDs")
        .Range(AtLeast(0))
        .Help("Filter: robust SDs below the first pass's median score a point may lie (0 = off); "
              "the pmvs passes' from their own first pass's"));
  f(Field(o.depth_tolerance, "depth_tolerance")
        .Flag("--depth-tolerance")
        .In(s)
        .Unit("footprints")
        .Range(Above(0))
        .Help("Filter: depth agreement, pixel footprints"));
  f(Field(o.neighbour_radius, "neighbour_radius")
        .Flag("--neighbour-radius")
        .In(s)
        .Unit("footprints")
        .Range(Above(0))
        .Help("Filter: neighbourhood radius, footprints"));
  f(Field(o.min_neighbours, "min_neighbours")
        .Flag("--min-neighbours")
        .In(s)
        .Unit("points")
        .Range(AtLeast(0))
        .Help("Filter: neighbours a point needs"));
  f(Field(o.plane_tolerance, "plane_tolerance")
        .Flag("--plane-tolerance")
        .In(s)
        .Unit("footprints")
        .Range(Above(0))
        .Help("Filter: distance to the local plane, footprints"));
  f(Field(o.plane_sigmas, "plane_sigmas")
        .Flag("--plane-sigmas")
        .In(s)
        .Unit("robust SDs")
        .Range(AtLeast(0))
        .Help("Filter: plane tolerance in robust SDs of the distances between patches"));
  f(Field(o.min_cluster_size, "min_cluster_size")
        .Flag("--min-cluster")
        .In(s)
        .Unit("points")
        .Range(AtLeast(0))
        .Help("Filter: smallest cluster kept, points"));
}

}  // namespace sapmvs

#pragma once
// Every kernel limit and tunable default lives here, and only here. Each .cl
// file keeps an `#ifndef NAME / #define NAME default` fallback so it compiles on
// its own (e.g. in an offline compiler), but the host always passes the value
// from this header as `-D NAME=VALUE`, so the fallbacks never decide anything
// in a real run. Change a value here, not in a kernel.

namespace sapmvs {

// Work-items per work-group for 1-D kernels. 64 is a multiple of every
// vendor's SIMD width (NVIDIA 32, AMD 64, PoCL vectorises across it) and far
// below any device's CL_DEVICE_MAX_WORK_GROUP_SIZE.
inline constexpr int kDefaultWorkGroupSize = 64;

// Work-items per work-group of the polish refinements (the larger adaptive
// sizes, patch_engine.cc) where a work-item refines a patch (CPUs;
// RefineLayout). Their launches hold tens to hundreds of patches: in groups
// of 64 that was one to three work-groups, so one of PoCL's threads often
// refined them all while the other waited.
inline constexpr int kPolishWorkGroupSize = 8;

// Work-items of one patch in patch_refine_group.cl, the refinement GPUs run
// (RefineLayout): a power of two, so that each NCC's sums reduce in a tree;
// about two to seven samples each (7 x 7 has 49, 21 x 21 441).
inline constexpr int RefineGroupWorkItems(int patch_size) {
  return patch_size * patch_size <= 64 ? 32 : 64;
}

// Largest side of a square matching window, in pixels (odd). Bounds the
// per-work-item private arrays of the NCC kernels.
inline constexpr int kMaxPatchSize = 21;

// Side of the PMVS matching patch (μ in method.md 3.1, PMVS2's `wsize`), in
// samples (odd). NccScorerOptions::patch_size defaults to it.
inline constexpr int kDefaultPatchSize = 7;

// Smallest per-sample variance (grey levels^2, images in 0..255) a sample
// vector of the NCC kernels may have; below it the NCC is NaN. 1e-4 is a
// standard deviation of 0.01 grey levels: far above the float32 rounding
// noise of sampling a flat image (about 1e-10) and far below any real texture,
// so only genuinely flat (or saturated) patches are rejected.
inline constexpr float kNccMinVariance = 1e-4f;

// Smallest spread (standard deviation, grey levels) of the 3 x 3 centre
// samples that the NCC sample weights scale from (NCC_SIGMA_COLOR times
// it). The weights are relative to the centre's texture so that one sigma
// suits any contrast; on weak texture (mown grass, a dirt road, haze) that
// spread is the images' noise, and the weights kept a few samples of each
// window. With this floor such windows score as plain NCC while a roof edge
// or a crown (tens of grey levels) keeps its weights. Against no floor,
// level 1: the Caliterra flight's ground covered 96.3 -> 96.6 % of its
// union with PMVS2's, NCC evaluations per point 74.1 -> 71.5; `small` and
// `city` within 1 GSD of the truth 91.9 / 89.5 -> 91.9 / 89.7 %;
// Herz-Jesu-P8 85.8 -> 85.9 % of PMVS2's points within 2 GSD (3: the same
// within 0.3 points; 4: Herz-Jesu-P8 85.6 %).
inline constexpr float kNccWeightMinSpread = 2.0f;

// Most views (reference + searches) one matching kernel call combines. Bounds
// the per-work-item arrays of the multi-view kernels.
inline constexpr int kMaxViews = 8;

// Largest image side the float32 kernels accept, in pixels. Float coordinates
// are exact integers only up to 2^24, so beyond this a pixel centre could not
// be addressed exactly.
inline constexpr int kMaxImageSide = 1 << 24;

// Deepest pyramid level (0 = full resolution, each level halves both sides)
// that matching, planning and export accept: 1/64 of a 10,000-pixel side is
// still a usable image.
inline constexpr int kMaxLevel = 6;

// Patch refinement (kernels/patch_refine.cl, PatchRefinerOptions). Each
// iteration polls up to 6 candidates (+- one step on depth, yaw and pitch),
// moves to the first that improves, and halves the steps when none does. 24 iterations take the
// tests' patches (started 2.5 footprints and 15 degrees off) to convergence; more change the result
// by less than 1e-3 NCC there.
inline constexpr int kDefaultRefineIterations = 24;
// A search stops early once its steps have been halved this many times: 4
// leaves depth steps of 1/16 footprint and angle steps of 0.5 degrees, so a
// centre lies within 1/32 footprint of the optimum on its lattice (1/16 GSD at
// level 1, 1/32 at level 0) and the corner of a 21 x 21 patch within 0.05
// footprints. Each halving costs a round that scores all 6 candidates for no
// move: 8 halvings were half of a PMVS-mode refinement's scores. From 8 to 4
// (first-improvement polling, level 1): PMVS mode 38 % less device time on
// city, 90.3 % of the points within 1 GSD against 90.4 %, coverage 57.9 %
// against 58.1 %; `small` 96.3 % in both, sapmvs mode 91.8 % against 91.9 %.
inline constexpr int kDefaultRefineHalvings = 4;
// Largest spacing of a patch grid's samples, in reference pixels
// (NccScorerOptions::sample_step): beyond 4 a bilinear sample no longer
// stands for the pixels between it and the next.
inline constexpr double kMaxSampleStep = 4.0;
// Largest iteration count accepted; bounds one work-item's run time.
inline constexpr int kMaxRefineIterations = 1000;
// Initial depth step, in reference-pixel footprints (depth / f).
inline constexpr double kDefaultRefineDepthStep = 1.0;
// Initial yaw / pitch step, in degrees.
inline constexpr double kDefaultRefineAngleStepDeg = 8.0;
// Largest angle (degrees) between a candidate's normal and the direction to
// the reference camera: beyond it the patch is seen too obliquely. The
// matcher passes its view_angle_deg instead.
inline constexpr double kDefaultRefineMaxAngleDeg = 80.0;

// An expansion candidate starts on its parent's plane, a fraction of a
// footprint from where it settles, so its search starts at half the seeds'
// steps and halves them once less: the same final steps (1/16 footprint,
// 0.5 degrees) for one round of 6 scores fewer. The 7 x 7 refinement's NCC
// scores per refined patch fell 15 % on `small` and `city` at level 1, with
// the points within 1 GSD of the truth 91.7 / 89.7 % against 91.7 / 89.8 %
// and coverage 80.0 / 75.9 % against 80.2 / 75.8 %. Quarter steps with two
// halvings saved 30 % but lost 0.7 points of coverage on `city`: a roof's
// candidate then could not turn its normal far enough.
inline constexpr double kExpansionRefineDepthStep = 0.5;
inline constexpr double kExpansionRefineAngleStepDeg = 4.0;
inline constexpr int kExpansionRefineHalvings = 3;
// A pmvs pass's one-cell patch (PatchEngine::Role::kOneCellPass) emits its
// centre alone, which the filter then holds to its neighbours' plane within
// half a footprint or more: its search stops one halving earlier, at depth
// steps of 1/8 footprint. That pass was two thirds of the propagation's time
// on `small` (80,293 candidates for 33,054 points); with 3 halvings against
// 2 its wave time went 1.19 -> 0.92 s, and on `small` and `city` the points
// within 1 GSD of the truth stayed 91.7 / 89.5 %, coverage 79.8 -> 79.7 %
// and 75.3 -> 75.2 %, local noise 1.12 -> 1.10 cm and 4.25 -> 4.15 cm.
inline constexpr int kOneCellRefineHalvings = 2;
// Those searches, started on a neighbour's plane one cell away, moved 13
// times on average on Herz-Jesu-P8 at level 1 (a 7 x 7 window hardly pins
// a normal down, so the search wanders along its score's flat ridges): 36
// scores a patch, 62 % of the run's NCC evaluations. Patches of more than 12
// moves took 60 % of that pass's scores, and 44 % of those that ran all 24
// rounds were rejected. So that pass's search has 12 rounds; and a
// candidate whose parent's plane already scores kOneCellDepthOnlyScore in
// every view acceptance needs (before refinement) only searches its depth
// (NccPatch::directions), keeping its parent's normal: half of that pass's
// candidates, whose normals the 7 x 7 window could not have improved on
// measurably. On Herz-Jesu-P8 NCC evaluations per point 138.4 -> 90.1;
// within 1 GSD of the truth `small` 91.7 -> 91.8 %, `city` 89.5 %; coverage
// 79.7 -> 79.5 % and 75.2 -> 74.5 %; PMVS2's points within 2 GSD of ours
// 93.8 -> 93.2 %, 91.0 -> 90.2 %, 86.1 -> 85.6 % (versus_pmvs2
// --pmvs2-cloud, the same PMVS2 clouds). Either alone saved less for the
// same loss (12 rounds: 111.2 per point; depth only from 0.9: 105.4).
inline constexpr int kOneCellRefineIterations = 12;
inline constexpr double kOneCellDepthOnlyScore = 0.9;

// Polishing (sapmvs mode, patch_engine.h): a patch refined at the window
// size is refined again, briefly, at each larger adaptive size. Its depth is
// already within a fraction of a footprint, but a 7 x 7 window pins its
// normal down only to several degrees, and a large patch's corners magnify
// that: 6 rounds from 2 degree steps could neither move the normal far
// enough nor refine it below the 2 degree grid (`small` at level 0: 90.1 % of
// the points within 1 GSD; 8 rounds from 4 degrees: 92.9 %, for 5 % more
// time). Iterations, initial depth step (footprints) and angle step (degrees).
inline constexpr int kPolishIterations = 8;
inline constexpr double kPolishDepthStep = 0.25;
inline constexpr double kPolishAngleStepDeg = 4.0;

}  // namespace sapmvs

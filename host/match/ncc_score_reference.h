#pragma once
// The NCC score of patches in views (patch_kernel_types.h describes the
// patch grid), in double precision from the same float inputs as
// kernels/ncc_score.cl, with the same geometry and NaN rules: what the kernel
// is tested against, and what the CPU backend (reference_patch_kernels.h)
// scores with.

#include <vector>

#include "match/patch_kernel_types.h"

namespace sapmvs {

// The scale s of the weighted NCC's sample weights exp(-d^2 / 2 s^2), as
// ncc_weights in ncc.cl: `sigma` standard deviations of the `n` samples
// `values` around the window's centre (its 3 x 3; fewer where an image's
// border clips them), their spread taken as at least kNccWeightMinSpread.
double NccWeightScale(const double* values, int n, double sigma);

// scores[i] = NCC of pairs[i], NaN where undefined. Validates the options,
// the group and the batch first (throws Error naming the first fault).
// `border_margin`, if given, receives per pair the smallest distance in
// pixels from any sample position to the edge of its image's valid region
// (negative outside): where it is within float32 rounding of 0 the kernel may
// legitimately decide the other way. `sigma_color`: as
// NccScorerOptions::sigma_color, `sample_step` as NccScorerOptions::sample_step.
// Pairs are scored in parallel (OpenMP).
std::vector<double> NccScoreReference(const NccGroup& group, const std::vector<NccPatch>& patches,
                                      const std::vector<NccPair>& pairs, int patch_size,
                                      std::vector<double>* border_margin = nullptr,
                                      double sigma_color = 0.0, double sample_step = 1.0);

// The score of one patch in `view` for callers that validated the group, the
// patch, the view and the options already (the refinement scores thousands of
// candidates per patch). `border_margin` as above, may be null.
double NccScoreReferenceUnchecked(const NccGroup& group, const NccPatch& patch, int view,
                                  int patch_size, double sigma_color, double* border_margin,
                                  double sample_step = 1.0);

}  // namespace sapmvs

#pragma once
// Patch planes from the neighbouring patches' centres (sapmvs mode).
//
// A sapmvs patch writes a point at every pixel of its window onto its plane,
// but only its centre's depth is what the search pinned down: the normal of
// a 7 x 7 to 21 x 21 window barely changes its score, and on `city` the
// points 3 px from a 7 x 7 centre were within 1 GSD of the truth in 55 %
// of cases against 77 % at the centre. The centres of the patches around it
// are independent measurements of the same surface (each was refined and
// accepted on its own), and the plane through its centre that fits theirs
// has a baseline of several windows, not one.
#include <Eigen/Core>
#include <vector>

#include "match/group_data.h"
#include "match/patch_engine.h"
#include "sapmvs/match/matcher_options.h"

namespace sapmvs {

// Points of a patch whose plane no neighbour confirms are kept only this many
// pixels from its centre (the centre's 3 x 3): the samples that decided its
// depth, not the extrapolation of a normal the score hardly constrains.
inline constexpr int kUnfittedReach = 1;

// For each patch p with alive[p], the unit normal, facing p's reference, of
// the plane through p's centre that best fits (least squares, each offset
// scaled to unit length so that near and far neighbours weigh alike) the
// centres of its options.refit_neighbours nearest patches that lie within
// (size + 4) footprints along its plane's slope (SlopeFootprint: one window
// and the propagation's step) and within options.refit_tolerance footprints
// of p's own plane (so that a roof's patches do not tilt the ground's). Zero
// when fewer than 3 such centres, when they lie along a line, or when the
// fitted plane faces the reference more obliquely than view_angle_deg. All
// zero when options.refit_neighbours is 0.
std::vector<Eigen::Vector3d> FitPatchNormals(const MatchGroupData& group,
                                             const MatcherOptions& options,
                                             const std::vector<AcceptedPatch>& patches,
                                             const std::vector<uint8_t>& alive);

}  // namespace sapmvs

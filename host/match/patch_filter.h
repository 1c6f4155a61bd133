#pragma once
// Filtering of the matched points (method.md 3.9). Points of patches that
// score below the caller's score floor go first; then three passes:
//  1. visibility: per image, a depth buffer on the cell grid from every
//     point's reference and photo-consistent views. A point is occluded in an
//     image where the front-most surface of its cell lies more than
//     depth_tolerance footprints in front of it; it must be unoccluded in at
//     least min_image_num images. A cell whose front-most points carry less
//     support (num_views x score) than the points they hide counts those
//     front points as occluding outliers, and they go (PMVS's filter 1).
//     Free space: a point lying in front of a surface that an image it was
//     not matched in did match there (so that image saw through it) goes when
//     that surface carries more support than the point;
//  2. neighbourhood: a point needs min_neighbours points within
//     neighbour_radius footprints and must lie within the plane tolerance of
//     the plane they fit, and a patch's plane must pass within it of most
//     points of other patches around it (not a one-cell patch's, see
//     FilterPoints). The tolerance is plane_sigmas robust
//     standard deviations of those patch-to-patch distances, at least
//     plane_tolerance footprints; for a pmvs pass's one-cell patch whose
//     depth its views resolve to within pmvs_pass_plane_tolerance footprints
//     (DisparityDepth), at least that;
//  3. clusters: points linked within neighbour_radius footprints form
//     clusters; those smaller than min_cluster_size go.
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "match/group_data.h"
#include "match/propagation.h"
#include "sapmvs/match/match_stats.h"
#include "sapmvs/match/matcher_options.h"

namespace sapmvs {

// How the filter tells a group's patches apart: sapmvs mode's pmvs passes'
// one-cell patches are those from `one_cell_first` on (none by default).
// Their points meet their own score floor: they score plain NCC over one
// window_size window, on another scale than the adaptive patches' weighted
// NCC (on `small` medians 0.92 and 0.985), and the adaptive patches' fence
// cut most of them, walls and all. And the patch-support test does not
// judge their planes (FilterPoints).
struct PatchClasses {
  PatchClasses(double all = 0) : floor(all), one_cell_floor(all) {}  // NOLINT: one floor for all
  double floor = 0;
  size_t one_cell_first = std::numeric_limits<size_t>::max();
  double one_cell_floor = 0;
  bool OneCell(int patch) const { return static_cast<size_t>(patch) >= one_cell_first; }
  double FloorOf(int patch) const { return OneCell(patch) ? one_cell_floor : floor; }
};

// The depth, in footprints of its reference at its centre, by which a pixel
// of disparity in the best placed of its views moves a patch's centre along
// its reference's ray: the least over its views of the view's footprint over
// the sine of the angle between the two rays (infinity without views).
double DisparityDepth(const MatchGroupData& group, const AcceptedPatch& patch);

// Which of FilterPoints' tests run: all, or the score floor and the
// visibility test alone (MatcherOptions::visibility_only_filters), which
// leave the neighbourhood, plane-support and cluster tests, and the
// neighbour table that is most of the filter's time, to a later pass.
enum class FilterTests { kAll, kScoreAndVisibility };
// keep[i] for points[i]; stats' removed_* counters and plane_tolerance are
// filled (plane_tolerance by kAll only). Points of patches scoring below
// their floor (`classes`) go first (removed_score) and take no part in the
// other passes.
std::vector<bool> FilterPoints(const MatchGroupData& group, const MatcherOptions& options,
                               const std::vector<DensePoint>& points,
                               const std::vector<AcceptedPatch>& patches, MatchStats* stats,
                               const PatchClasses& classes = PatchClasses(),
                               FilterTests tests = FilterTests::kAll);

// The score floor of the points of patches `first_patch` on (their
// patches' scores): `options.threshold`, raised to median - score_fence
// robust standard deviations (1.4826 MAD) when score_fence > 0 and there are
// at least 10 such points. Taken from the first expansion's points, it keeps
// the weakest matches of a block out.
double ScoreFloor(const MatcherOptions& options, const std::vector<DensePoint>& points,
                  const std::vector<AcceptedPatch>& patches, size_t first_patch = 0);

// Per image, the depths a point may lie at in it as its reference. Beyond
// the seeds: Tukey's far fence on the image's seed depths (3 interquartile
// ranges beyond the third quartile) plus 10 `gsd`. A false match can grow
// into a cluster big enough to pass the cluster filter (on the NGI block,
// clusters kilometres below the ground); quartiles, not the seeds'
// extremes, because false seeds are among them. Those false seeds pile up at
// the far end of the epipolar search (NGI: 9-10 km behind ground at 5 km;
// `city`: 800-1000 m behind ground at 500 m), below the ground, where a nadir
// block has nothing to see. In front of the seeds stand buildings and
// towers, which few seeds hit: Tukey's near fence cut `city`'s 66 m tower
// (its roof 13 % nearer than the ground) out of the cloud. So the near
// fence is the nearer of Tukey's and `search_near[i]`, the nearest depth the
// seed search looked at (0: none given, Tukey's). (0, 0) = no fence, when an
// image has fewer than 10 seeds.
std::vector<std::pair<double, double>> SeedDepthFences(
    const std::vector<std::vector<double>>& seed_depths, const std::vector<double>& search_near,
    double gsd);

// Clears keep[i] for kept points outside their reference image's fence;
// returns how many.
long ApplyDepthFences(const MatchGroupData& group, const std::vector<DensePoint>& points,
                      const std::vector<AcceptedPatch>& patches,
                      const std::vector<std::pair<double, double>>& fences,
                      std::vector<bool>* keep);

// The visibility pass alone (tests): keep[i] after pass 1, among the points
// where `eligible` is true (all when empty).
std::vector<bool> VisibilityFilter(const MatchGroupData& group, const MatcherOptions& options,
                                   const std::vector<DensePoint>& points,
                                   const std::vector<AcceptedPatch>& patches,
                                   const std::vector<bool>& eligible = {});

}  // namespace sapmvs

#pragma once
// Filtering of the matched points (method.md 3.5), in three passes:
//  1. visibility: per image, a depth buffer on the cell grid from every
//     point's reference and photo-consistent views. A point is occluded in an
//     image where the front-most surface of its cell lies more than
//     depth_tolerance footprints in front of it; it must be unoccluded in at
//     least min_image_num images. A cell whose front-most points carry less
//     support (num_views x score) than the points they hide counts those
//     front points as occluding outliers, and they go (PMVS's filter 1).
//  2. neighbourhood: a point needs min_neighbours points within
//     neighbour_radius footprints and must lie within plane_tolerance
//     footprints of the plane they fit;
//  3. clusters: points linked within neighbour_radius footprints form
//     clusters; those smaller than min_cluster_size go.
#include <vector>

#include "match_group.h"
#include "propagation.h"
#include "sapmvs/matcher.h"

namespace sapmvs {

// keep[i] for points[i]; stats' removed_* counters are filled.
std::vector<bool> FilterPoints(const MatchGroupData& group, const MatcherOptions& options,
                               const std::vector<DensePoint>& points,
                               const std::vector<AcceptedPatch>& patches, MatchStats* stats);

// The visibility pass alone (tests): keep[i] after pass 1.
std::vector<bool> VisibilityFilter(const MatchGroupData& group, const MatcherOptions& options,
                                   const std::vector<DensePoint>& points,
                                   const std::vector<AcceptedPatch>& patches);

}  // namespace sapmvs

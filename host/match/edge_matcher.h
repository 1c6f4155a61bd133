#pragma once
// Edge points matched along epipolar lines (the paper's addition to PMVS's
// seeds, method.md 3.7). Each Canny edge pixel of an image is searched for
// along its epipolar segment in the image's best view, within the depth range
// its seeds span: the edge pixels of the view on the segment are triangulated
// and scored (window_size NCC, fronto-parallel to the reference, on the
// device, all images in one launch). The best candidate is kept when it
// reaches `threshold`, is confirmed by a second view at threshold_before when
// there is one, and no candidate more than 2 px away along the line comes
// within kEdgeAmbiguity of it. Propagation then treats matched edge points
// that lie off a patch's plane as barriers.
#include <utility>
#include <vector>

#include "match/group_data.h"
#include "match/patch_engine.h"
#include "match/propagation.h"

namespace sapmvs {

inline constexpr float kEdgeAmbiguity = 0.05f;

struct EdgeMatchStats {
  long edge_pixels = 0;
  long matched = 0;
};

// depth_range[i] = (min, max) depth of image i's scene; an image with an
// empty range (min >= max) gets an empty EdgeMap.
std::vector<EdgeMap> MatchEdges(const MatchGroupData& group, const MatcherOptions& options,
                                const std::vector<std::pair<double, double>>& depth_range,
                                PatchEngine& engine, EdgeMatchStats* stats);

}  // namespace sapmvs

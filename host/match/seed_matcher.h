#pragma once
// Seed candidates (method.md 3.4): for each feature of each image, features
// of the same kind within `epipolar_distance` pixels of its epipolar line in
// the image's views are triangulated, and the resulting points are ordered by
// depth consistency: how many further views hold a same-kind feature within
// that distance of the point's projection, then by epipolar distance.
#include <Eigen/Core>
#include <functional>
#include <vector>

#include "match/feature_detector.h"
#include "match/group_data.h"
#include "match/patch_engine.h"

namespace sapmvs {

struct SeedFeature {
  int image = -1;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  std::vector<PatchCandidate> candidates;  // best first
};

// Depths a seed may have, as a factor of the image's expected scene depth:
// wide enough for any relief an aerial or close-range block brings, narrow
// enough to keep epipolar segments short.
inline constexpr double kSeedDepthMin = 0.5;
inline constexpr double kSeedDepthMax = 2.0;

// The seeds of the reference features `wanted` says (image, feature) are
// (all when empty); every feature of the views stays a partner.
std::vector<SeedFeature> MatchSeeds(const MatchGroupData& group,
                                    const std::vector<std::vector<Feature>>& features,
                                    const MatcherOptions& options,
                                    const std::function<bool(int, const Feature&)>& wanted = {});

// Midpoint of the shortest segment between the rays through uv_a in camera a
// and uv_b in camera b; NaN when the rays are parallel.
Eigen::Vector3d TriangulateMidpoint(const Camera& a, const Eigen::Vector2d& uv_a, const Camera& b,
                                    const Eigen::Vector2d& uv_b);

}  // namespace sapmvs

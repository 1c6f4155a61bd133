#pragma once
// Footprints: the lengths that the matcher's distances are counted in.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "sapmvs/block/camera.h"

namespace sapmvs {

// Host twin of NCC_MIN_FORESHORTENING (kernels/ncc.cl): the smallest share
// of its face-on length that a direction on a plane may keep in an image,
// the cosine of 84 degrees. The NCC grid does not score planes seen more
// obliquely, and SlopeFootprint divides by no smaller cosine.
inline constexpr double kMinForeshortening = 0.1;

// One pixel of `camera` at x, seen face-on: depth / f.
inline double Footprint(const Camera& camera, const Eigen::Vector3d& x) {
  return camera.Depth(x) / camera.intrinsics().MeanFocal();
}

// One pixel of `camera` at x on the plane with unit normal n, along the
// plane's slope: the face-on footprint over the cosine of the angle between
// n and the line of sight. Seen at 81 degrees (Herz-Jesu-P8's ground from
// its cameras at 1.6 m), neighbouring pixels lie 6.4 face-on footprints
// apart on the surface, and its depths within one cell of the image spread
// as far, so radii and depth tolerances counted in face-on footprints take a
// grazing surface's points for outliers of each other.
inline double SlopeFootprint(const Camera& camera, const Eigen::Vector3d& x,
                             const Eigen::Vector3d& n) {
  const double cosine = std::abs((camera.center() - x).normalized().dot(n));
  return Footprint(camera, x) / std::max(cosine, kMinForeshortening);
}

}  // namespace sapmvs

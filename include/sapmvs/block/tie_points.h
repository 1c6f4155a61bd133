#pragma once
// Tie points: the scene's depth from the block itself, for blocks that bring
// no DEM, no sparse points and no ground height (a PMVS folder, a COLMAP
// model without points3D). Features are matched between neighbouring images
// along their epipolar lines with no bound on depth, chained into tracks and
// triangulated; a track counts once it is seen in min_views images and
// reprojects within a few pixels in each, as PMVS's own seeds do. Unlike the
// intersection of optical axes, which says nothing about depth when the axes
// are near-parallel (the normal case of aerial and UAV blocks), this measures
// depth wherever the images overlap.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"

namespace sapmvs {

struct TiePointOptions {
  // Images are halved until their longer side is at most this many pixels:
  // depth needs only a median per image. SIFT doubles the image first, so at
  // 1,200 px its pyramid took ~180 MB per image and set a whole run's peak
  // memory (small: 482 MiB before matching began). At 400 px (small's 1,000
  // px images at 250, the Caliterra flight's 2,000 at 250) the median GSD
  // of `small` and `city` is within 0.5 % of their DEMs', as at 600 px, and
  // the plan takes 0.2 s instead of 0.5 s on `small` (1.4 s instead of 3.0
  // on Caliterra's 75 images).
  int max_side = 400;
  // Images detected at once (each with OpenCV's own threads): two keep two
  // cores busy for about 60 MB more than one, below the matching's peak.
  int concurrent_images = 2;
  // SIFT features kept per image (strongest first).
  int features = 2000;
  // Each image is matched with this many others, nearest projection centres
  // first among those whose optical axes are within max_axis_angle_deg.
  int neighbours = 6;
  double max_axis_angle_deg = 60.0;
  // A match lies within this many pixels (at the reduced size) of the
  // epipolar line of its feature.
  double epipolar_px = 1.5;
  // Lowe's ratio: the best epipolar candidate's descriptor distance must be
  // below this share of the next candidate's.
  double ratio = 0.8;
  // Images a track needs (2 for a block of 2 images).
  int min_views = 3;
  // A track's observations must reproject within this many pixels (reduced
  // size), and its rays span at least min_angle_deg.
  double max_reprojection_px = 2.0;
  double min_angle_deg = 1.0;

  // "" or the first failing condition as "what was expected (name = value)".
  std::string Problem() const;
};

struct TiePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world frame
  std::vector<int> images;                             // block indices, ascending
};

// Tie points of `block` (world frame). Images without a file (camera-only
// blocks) are skipped; a block with fewer than 2 images with files gives
// none. Throws Error naming the image for unreadable files, and for bad
// options.
std::vector<TiePoint> TriangulateTiePoints(const Block& block, const TiePointOptions& options = {});

}  // namespace sapmvs

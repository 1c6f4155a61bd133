#pragma once
// One group of images prepared for matching: pixels at the working pyramid
// level, pinhole cameras in the block's local frame, the views each image is
// matched with, and the depth range its scene is expected in.
#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "match/patch_kernel_types.h"
#include "sapmvs/block/block.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/camera.h"
#include "sapmvs/block/image_io.h"

namespace sapmvs {

class LevelImageStore;

struct MatcherOptions;

struct MatchImage {
  std::string name;
  int block_index = -1;
  Camera camera;  // local frame, working level, no distortion
  // CV_32F, grey levels 0..255; a view into the group's one block of pixels,
  // which MatchGroupData::ncc.pixels owns (LoadMatchGroup).
  cv::Mat grey;
  // The image file when it was loaded: LoadColorAtLevel reads it again and
  // refuses a file that has changed since.
  FileStamp file;
  std::vector<int> views;  // other images of the group to match with, best first
  double depth = 0;        // expected scene depth along the optical axis
  // False for a view-only image (another strip's, ImageGroup::views): patches
  // are matched in it, but no seed, patch or point takes it as reference.
  bool reference = true;
};

struct MatchGroupData {
  std::vector<MatchImage> images;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double gsd = 0;  // median footprint of a working pixel at the expected depth
  NccGroup ncc;    // views of `images` for the patch kernels (valid while images live)
};

// Loads (undistorted) images `ids` of `block` and reduces them to `level`
// with 2x2 area averaging, so pixel centres stay where Camera::Scaled puts
// them. Throws Error naming the image for unreadable files.
// `geometry`: EstimateBlockGeometry(block) when the caller has it (a
// whole-block run loads many groups of one block; estimating it reads the
// block's DEM each time), else nullptr and it is estimated here. `levels`:
// the run's store of images at the level (level_images.h), else nullptr
// and each image is decoded.
MatchGroupData LoadMatchGroup(const Block& block, const std::vector<int>& ids, int level,
                              const BlockGeometry* geometry = nullptr,
                              const LevelImageStore* levels = nullptr);

// The colour pixels of group image `image` (CV_8UC3, BGR), read again from
// its file as LoadMatchGroup read it: the group keeps only grey levels
// through the matching, and its points take their colours once they are
// known. Throws Error naming the image for an unreadable file, or one whose
// size or time differ from the load's (replaced during the run: its pixels
// would not be the ones matched). `levels` as for LoadMatchGroup.
cv::Mat LoadColorAtLevel(const Block& block, const MatchImage& image, int level,
                         const LevelImageStore* levels = nullptr);

// Picks each image's views: images whose footprint overlaps its own at the
// expected depth, most overlap first, at most kMaxViews - 1. As in PMVS2,
// views narrower than max_angle_deg take part: the angle condition applies
// to the views a patch is matched in (PatchEngine), not to each view.
void SelectViews(const MatcherOptions& options, MatchGroupData* group);

// Angle, degrees, between the rays from camera centres a and b to x.
double TriangulationAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& x);

}  // namespace sapmvs

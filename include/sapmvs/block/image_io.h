#pragma once
// Reading images: sizes from the file header (GDAL, no decoding), pixels
// through OpenCV, undistortion once at load so the matcher sees pinhole images.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"

namespace sapmvs {

// A file's size and modification time, the two a replaced file changes.
struct FileStamp {
  std::uintmax_t size = 0;
  std::filesystem::file_time_type time{};
  bool operator==(const FileStamp& o) const { return size == o.size && time == o.time; }
  bool operator!=(const FileStamp& o) const { return !(*this == o); }
  // None where either cannot be read (a removed file).
  static std::optional<FileStamp> Of(const std::filesystem::path& path);
};

struct ImageSize {
  int width = 0;
  int height = 0;
};

// Reads the size from the header; throws naming the file when it is missing or
// not an image GDAL can open.
ImageSize ReadImageSize(const std::filesystem::path& path);

// Finds the image called `name` in `folder`: the exact file name first, then
// a file whose stem is `name` (or `name`'s stem) with an image extension.
// Returns an empty path when none is found; throws sapmvs::Error naming both
// files when two fit (a.jpg and a.png for `a`).
std::filesystem::path FindImageFile(const std::filesystem::path& folder, const std::string& name);

// True for the extensions the readers accept as images.
bool HasImageExtension(const std::filesystem::path& path);

// Loads the 8-bit colour image (BGR) of `image` and checks its size against
// the camera; throws naming the file otherwise.
cv::Mat LoadImage(const BlockImage& image);

// Resamples a distorted image to the pinhole camera with the same fx fy cx cy
// and size (bilinear). A camera without distortion returns `image` unchanged.
cv::Mat Undistort(const cv::Mat& image, const Intrinsics& intrinsics);

// An image ready for matching: undistorted pixels and the pinhole camera.
struct LoadedImage {
  cv::Mat pixels;  // 8-bit BGR
  Camera camera;   // no distortion
};
LoadedImage LoadUndistorted(const BlockImage& image);

// `image` at pyramid level `level`, to go with Camera::Scaled(2^-level) of
// size `width` x `height`: halved `level` times by averaging 2x2 blocks
// (INTER_AREA at exactly 1/2), so that output pixel i is centred at input
// 2i + 0.5 as Intrinsics::Scaled assumes (pyrDown would centre it at 2i),
// then resized to the camera's size where the rounding of odd sides differs.
cv::Mat ResampleToLevel(const cv::Mat& image, int level, int width, int height);

// The colour of an 8-bit BGR image at pixel coordinates (x, y) (pixel
// (0, 0)'s centre at 0), bilinear between the four pixels around it, border
// pixels repeated; BGR, unrounded.
Eigen::Vector3d BilinearBgr(const cv::Mat& bgr, double x, double y);

}  // namespace sapmvs

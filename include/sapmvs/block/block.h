#pragma once
// An oriented block of images: what every block reader produces and every
// later stage consumes. World coordinates are kept in double; `origin` is the
// block's local origin, and everything handed to the device is float32
// relative to it.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/block/camera.h"

namespace sapmvs {

struct BlockImage {
  std::string name;            // as the orientation source names it
  std::filesystem::path path;  // the image file
  std::string camera_name;     // the interior orientation it shares with others
  Camera camera;               // world frame, with the distortion of the raw image
};

struct Block {
  std::filesystem::path source;  // the file or folder that was read
  std::string format;            // reader that produced it: yaml, pmvs, colmap, strecha, opensfm
  std::string crs;               // CRS as given (WKT, EPSG:n, PROJ string); empty when unknown
  std::string frame_note;        // how to read the frame when no CRS is given
  std::vector<BlockImage> images;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // local origin (world frame)

  // What is known of the scene surface, best first: a DEM raster in the
  // block's frame, sparse points from the source, a mean ground height.
  std::filesystem::path dem;
  std::vector<Eigen::Vector3d> sparse_points;
  std::optional<double> ground_height;

  int FindImage(const std::string& name) const;  // -1 when absent
};

// A local origin for `images`: the mean projection centre, rounded to a round
// number three decades below the block's extent, so that offsets printed in
// headers stay readable and float32 keeps sub-millimetre steps.
Eigen::Vector3d ChooseLocalOrigin(const std::vector<BlockImage>& images);

}  // namespace sapmvs

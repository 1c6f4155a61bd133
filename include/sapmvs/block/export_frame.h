#pragma once
// The side file `sapmvs export` leaves in its folder, and the marker that
// proves a folder is an export's. PMVS2 and most MVS tools compute in float32,
// where UTM-sized coordinates lose centimetres, so exports are written in the
// block's local frame; the side file carries what is needed to put them back
// into the world frame, and the PMVS and COLMAP readers apply it.
//
//   DIR/sapmvs_frame.json  {"format": "pmvs", "level": 1,
//                           "origin": [X, Y, Z],       world = local + origin
//                           "crs": "EPSG:32632",       "" when unknown
//                           "source": "/abs/block.yaml",
//                           "sapmvs_version": "0.1.0",
//                           "images": ["name", ...],   original names, in order
//                           "ground_height": 300,      world frame; only if known
//                           "dem": "/abs/dem.tif"}     the block's DEM; only if any
//   DIR/.sapmvs_export     the files the export writes, one relative path a
//                          line; written first, so a folder whose export was
//                          interrupted is still known to be ours

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/block/block.h"

namespace sapmvs {

inline constexpr char kExportFrameFile[] = "sapmvs_frame.json";
inline constexpr char kExportMarkerFile[] = ".sapmvs_export";

struct ExportFrame {
  std::string format;  // pmvs | colmap
  int level = 0;       // pmvs: PMVS2's level; colmap: the images' pyramid level
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::string crs;
  std::string source;
  std::string sapmvs_version;
  std::vector<std::string> images;
  std::optional<double> ground_height;
  std::string dem;  // absolute; empty when the block has none
};

void WriteExportFrame(const std::filesystem::path& dir, const ExportFrame& frame);

// The side file of the export in `dir`; nullopt when `dir` is no export.
// Throws InputError naming the file when it is malformed, and Error when the
// marker says an export into `dir` was started but never finished (its files
// may be a mix of two exports).
std::optional<ExportFrame> ReadExportFrame(const std::filesystem::path& dir);

// Puts a block read from an export back into the world frame of the side
// file: cameras and sparse points moved by the origin, the CRS, the ground
// height, the DEM (when it is still there) and the images' original names
// (PMVS numbers them).
// Throws InputError when the side file was written for another format.
void ApplyExportFrame(const ExportFrame& frame, const std::filesystem::path& frame_dir,
                      const std::string& format, Block* block);

// The relative paths listed in `dir`'s marker (none when there is no marker);
// entries that would leave `dir` are dropped.
std::vector<std::filesystem::path> ReadExportMarker(const std::filesystem::path& dir);
void WriteExportMarker(const std::filesystem::path& dir,
                       const std::vector<std::filesystem::path>& files);

}  // namespace sapmvs

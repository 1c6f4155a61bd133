#pragma once
// `sapmvs export`: a block written for other dense matchers, with undistorted
// images and pinhole cameras in the block's local frame (export_frame.h says
// why, and what the side file holds).
//   pmvs    PMVS2/CMVS folder, run as `pmvs2 DIR/ option`:
//             visualize/NNNNNNNN.jpg  full resolution (PMVS2 applies its level)
//             txt/NNNNNNNN.txt        CONTOUR + P = K [R | t], 3 rows
//             models/                 empty, PMVS2 writes its clouds there
//             option                  PMVS2's defaults, with `level`
//   colmap  COLMAP text model:
//             images/NAME             at the level, in the source's format
//             sparse/0/cameras.txt    PINHOLE, one per distinct intrinsics
//             sparse/0/images.txt     world-to-camera quaternion + t
//             sparse/0/points3D.txt   the block's sparse points (may be none)
// Every file appears whole or not at all. A folder is only written when it is
// new, empty, or an earlier export's; a re-export removes the files of the
// earlier one that it does not write again.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "sapmvs/block/block.h"

namespace sapmvs {

enum class ExportFormat { kPmvs, kColmap };

// "pmvs" or "colmap"; throws Error (one line) otherwise.
ExportFormat ParseExportFormat(std::string_view text);
std::string ToString(ExportFormat format);

struct ExportOptions {
  // Output folder; created when missing.
  std::filesystem::path out;
  ExportFormat format = ExportFormat::kPmvs;
  // Pyramid level 0..6. pmvs: PMVS2's `level` in the option file, the images
  // stay at full resolution; colmap: images and cameras scaled by 2^-level.
  // Unset: the format's default, 1 for pmvs (PMVS2's), 0 for colmap.
  std::optional<int> level;
  // JPEG quality (1..100) of the images written as JPEG.
  int jpeg_quality = 95;
  // A line per image on stderr, on a terminal only (progress.h).
  bool progress = true;

  int Level() const;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
  bool Check() const;
};

// Throws Error ("DIR: ...") unless `out` may be written: missing, an empty
// folder, or the folder of an earlier export (export_frame.h's marker or side
// file proves it).
void CheckExportTarget(const std::filesystem::path& out);

struct ExportSummary {
  std::filesystem::path out;
  ExportFormat format = ExportFormat::kPmvs;
  int level = 0;
  int images = 0;
  int cameras = 0;  // distinct pinhole cameras (colmap); one per image for pmvs
  long points = 0;  // sparse points written (colmap)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
};

// Writes `block` as `options` say. Options, the target folder and every image
// name are checked before the first image is loaded.
ExportSummary ExportBlock(const Block& block, const ExportOptions& options);

}  // namespace sapmvs

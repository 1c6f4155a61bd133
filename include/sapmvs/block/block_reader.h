#pragma once
// Block readers. The format is detected from the path given (a file or a
// folder) unless BlockReadOptions::format names it.
//   yaml     native block.yaml (docs/running.md, "Inputs: block files")
//   pmvs     PMVS/CMVS folder: txt/NNNNNNNN.txt (CONTOUR + 3x4 P), visualize/
//   colmap   COLMAP model, binary (cameras.bin, images.bin + points3D.bin) or
//            text (cameras.txt, images.txt + points3D.txt); binary when a
//            folder has both, with a note on stderr
//   strecha  Strecha .camera files (K, distortion, R camera-to-world, C, W H)
//   opensfm  OpenSfM reconstruction.json (perspective, brown)

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "sapmvs/block/block.h"

namespace sapmvs {

enum class BlockFormat { kAuto, kYaml, kPmvs, kColmap, kStrecha, kOpenSfm };

// "auto", "yaml", "pmvs", "colmap", "strecha", "opensfm"; throws otherwise.
BlockFormat ParseBlockFormat(std::string_view text);
std::string ToString(BlockFormat format);

struct BlockReadOptions {
  // Format of the block; kAuto detects it from the path.
  BlockFormat format = BlockFormat::kAuto;
  // Folder holding the images, overriding where the format says they are.
  std::filesystem::path image_dir;
  // Compare every image's header size with its camera (cheap: no decoding).
  bool check_image_sizes = true;
  // Mean ground height, block units, replacing the block's own; for blocks
  // that carry no surface estimate. Finite.
  std::optional<double> ground_height;
  // The CRS of a block that is already projected but does not say so (a
  // COLMAP model aligned to UTM coordinates): WKT, "EPSG:n" or a PROJ
  // string. A block that names another CRS is refused.
  std::string crs;
  // The geodetic origin (latitude, longitude in degrees, WGS84; height in
  // metres) of a block in a local east-north-up frame about it (COLMAP's
  // model_aligner to ENU): the block is moved into the UTM zone there, as
  // an OpenSfM block is. A block whose camera centres lie at the Earth's
  // radius and which looks at the Earth's centre is read as ECEF (model
  // aligner to ECEF) and moved the same way without it.
  std::optional<Eigen::Vector3d> enu_origin;

  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
  bool Check() const;
};

// Detects the format of `path`; throws naming the path and what was looked
// for when nothing matches.
BlockFormat DetectBlockFormat(const std::filesystem::path& path);

// Reads a block. Every image gets its camera, its file and the block's local
// origin is chosen. Malformed input throws InputError (file:line: expected ...).
Block ReadBlock(const std::filesystem::path& path, const BlockReadOptions& options = {});

// The individual readers; `path` is what DetectBlockFormat accepted.
Block ReadYamlBlock(const std::filesystem::path& path, const BlockReadOptions& options);
Block ReadPmvsBlock(const std::filesystem::path& path, const BlockReadOptions& options);
Block ReadColmapBlock(const std::filesystem::path& path, const BlockReadOptions& options);
Block ReadStrechaBlock(const std::filesystem::path& path, const BlockReadOptions& options);
Block ReadOpenSfmBlock(const std::filesystem::path& path, const BlockReadOptions& options);

}  // namespace sapmvs

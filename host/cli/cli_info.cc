// `sapmvs info BLOCK`: what a block holds and what its geometry says.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "cli/cli.h"
#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"

namespace sapmvs::cli {
namespace {

struct InfoArgs {
  std::string block;
  BlockFlags flags;
};

std::string Fmt(const char* fmt, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, a, b, c);
  return buf;
}

void PrintInfo(const Block& block, std::ostream& out) {
  const BlockGeometry g = EstimateBlockGeometry(block);
  out << "block          " << block.source.string() << " (" << block.format << ")\n";
  // A CRS the reader derived (OpenSfM's reference point) comes with how.
  out << "frame          "
      << (block.crs.empty()          ? block.frame_note
          : block.frame_note.empty() ? "CRS " + block.crs
                                     : "CRS " + block.crs + " (" + block.frame_note + ")")
      << "\n";
  out << "local origin   "
      << Fmt("X %.3f  Y %.3f  Z %.3f", block.origin.x(), block.origin.y(), block.origin.z())
      << "\n";

  std::map<std::string, const Camera*> cameras;
  for (const BlockImage& im : block.images) cameras.emplace(im.camera_name, &im.camera);
  out << "cameras        " << cameras.size() << "\n";
  for (const auto& [name, cam] : cameras) {
    const Intrinsics& k = cam->intrinsics();
    out << "  " << name << ": " << k.width << "x" << k.height << " px, "
        << Fmt("fx %.3f fy %.3f cx %.3f", k.fx, k.fy, k.cx) << Fmt(" cy %.3f px", k.cy)
        << (k.distortion.IsZero() ? ", no distortion"
                                  : Fmt(", Brown k1 %.5g k2 %.5g k3 %.5g", k.distortion.k1,
                                        k.distortion.k2, k.distortion.k3) +
                                        Fmt(" p1 %.5g p2 %.5g (undistorted at load)",
                                            k.distortion.p1, k.distortion.p2))
        << "\n";
  }

  out << "images         " << block.images.size() << "\n";
  out << "    #  name                              size         X              Y              Z"
         "            GSD\n";
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& im = block.images[i];
    const Eigen::Vector3d& c = im.camera.center();
    char line[512];
    const std::string size =
        std::to_string(im.camera.width()) + "x" + std::to_string(im.camera.height());
    std::snprintf(line, sizeof(line), "  %3zu  %-32s  %-11s  %13.3f  %13.3f  %11.3f  ", i + 1,
                  im.name.c_str(), size.c_str(), c.x(), c.y(), c.z());
    out << line << (g.images[i].valid ? Fmt("%.4g", g.images[i].gsd) : std::string("?")) << "\n";
  }

  out << "surface from   " << ToString(g.source);
  if (g.source == SurfaceSource::kDem) out << " (" << block.dem.string() << ")";
  if (g.source == SurfaceSource::kSparsePoints)
    out << " (" << block.sparse_points.size() << " points)";
  if (g.source == SurfaceSource::kGroundHeight) out << Fmt(" (Z = %.3f)", *block.ground_height);
  if (g.source == SurfaceSource::kTiePoints) out << " (" << g.tie_points.size() << " points)";
  out << "\n";
  if (g.num_valid == 0) {
    // Not an error here: info shows what the block holds, and this is why
    // run and plan would refuse it.
    out << "GSD            unknown: " << NoSurfaceReason(block, g) << "\n";
    return;
  }
  out << "GSD            "
      << Fmt("%.4g .. %.4g (median %.4g) units per pixel", g.gsd_min, g.gsd_max, g.gsd_median)
      << (g.aerial ? ", on the ground" : ", facing the camera") << "\n";
  const Eigen::Vector3d size = g.extent_max - g.extent_min;
  if (g.aerial) {
    out << "flying height  " << Fmt("%.2f above the surface (mean)", g.flying_height) << "\n";
    out << "ground extent  " << Fmt("X %.2f .. %.2f, ", g.extent_min.x(), g.extent_max.x())
        << Fmt("Y %.2f .. %.2f: ", g.extent_min.y(), g.extent_max.y())
        << Fmt("%.1f x %.1f (area %.4g)", size.x(), size.y(), size.x() * size.y()) << "\n";
  } else {
    out << "mean distance  " << Fmt("%.3f to the scene along the optical axes", [&] {
      double s = 0;
      for (const ImageGeometry& ig : g.images) s += ig.valid ? ig.depth : 0;
      return s / g.num_valid;
    }()) << "\n";
    out << "scene extent   " << Fmt("X %.2f .. %.2f, ", g.extent_min.x(), g.extent_max.x())
        << Fmt("Y %.2f .. %.2f, ", g.extent_min.y(), g.extent_max.y())
        << Fmt("Z %.2f .. %.2f", g.extent_min.z(), g.extent_max.z()) << "\n";
  }
  if (g.num_valid < static_cast<int>(block.images.size())) {
    out << "note           " << block.images.size() - g.num_valid
        << " image(s) have no surface estimate\n";
  }
}

}  // namespace

void RegisterInfoCommand(CLI::App& app, const GlobalFlags& /*global*/) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Print a block's images, cameras, GSD range, local origin, flying height and extent");
  cmd->add_option("block", args->block,
                  "Block: block.yaml, PMVS/COLMAP/Strecha folder, or OpenSfM json")
      ->required();
  AddBlockFlags(cmd, &args->flags);
  cmd->callback([args] {
    const Block block = ReadBlockWithFlags(args->block, args->flags);
    PrintInfo(block, std::cout);
  });
}

void AddBlockFlags(CLI::App* cmd, BlockFlags* flags, const std::string& format_flag) {
  cmd->add_option(format_flag, flags->format,
                  "Block format: auto, yaml, pmvs, colmap, strecha, opensfm")
      ->capture_default_str();
  cmd->add_option("--image-dir", flags->read.image_dir,
                  "Folder holding the images (overrides the block's)");
  cmd->add_flag("!--no-size-check", flags->read.check_image_sizes,
                "Do not compare image headers with the camera sizes");
  cmd->add_option("--ground-height", flags->ground_height,
                  "Mean ground height (block units) for blocks that carry no surface estimate");
  cmd->add_option("--crs", flags->read.crs,
                  "CRS of a block already in projected coordinates that does not name it "
                  "(EPSG:n, WKT or a PROJ string)");
  cmd->add_option("--enu-origin", flags->enu_origin,
                  "LAT,LON,H: the origin of a block in a local east-north-up frame (COLMAP "
                  "aligned to ENU); outputs go to the UTM zone there (write --enu-origin=... "
                  "when LAT is negative)")
      ->delimiter(',')
      ->allow_extra_args(false);
}

BlockReadOptions ReadOptionsOf(const BlockFlags& flags) {
  BlockReadOptions read = flags.read;
  read.format = ParseBlockFormat(flags.format);
  if (!std::isnan(flags.ground_height)) read.ground_height = flags.ground_height;
  if (!flags.enu_origin.empty()) {
    if (flags.enu_origin.size() != 3) {
      throw Error("--enu-origin has " + std::to_string(flags.enu_origin.size()) +
                  " values; expected LAT,LON,H (degrees, degrees, metres), e.g. "
                  "47.3769,8.5417,408");
    }
    read.enu_origin =
        Eigen::Vector3d(flags.enu_origin[0], flags.enu_origin[1], flags.enu_origin[2]);
  }
  return read;
}

Block ReadBlockWithFlags(const std::string& path, const BlockFlags& flags) {
  return ReadBlock(path, ReadOptionsOf(flags));
}

}  // namespace sapmvs::cli

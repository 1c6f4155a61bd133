#include "sapmvs/block/block_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <iostream>
#include <map>
#include <sstream>

#include "block/block_georeference.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/input_file.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

bool IsPmvsFolder(const fs::path& dir) {
  if (!fs::is_directory(dir / "txt")) return false;
  for (const auto& e : fs::directory_iterator(dir / "txt")) {
    const std::string stem = e.path().stem().string();
    if (e.path().extension() == ".txt" && stem.size() == 8 &&
        std::all_of(stem.begin(), stem.end(), [](char c) { return std::isdigit(c); })) {
      return true;
    }
  }
  return false;
}

bool HasCameraFiles(const fs::path& dir) {
  if (!fs::is_directory(dir)) return false;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".camera") return true;
  }
  return false;
}

}  // namespace

BlockFormat ParseBlockFormat(std::string_view text) {
  if (text == "auto") return BlockFormat::kAuto;
  if (text == "yaml") return BlockFormat::kYaml;
  if (text == "pmvs") return BlockFormat::kPmvs;
  if (text == "colmap") return BlockFormat::kColmap;
  if (text == "strecha") return BlockFormat::kStrecha;
  if (text == "opensfm") return BlockFormat::kOpenSfm;
  throw Error("unknown block format '" + std::string(text) +
              "': expected auto, yaml, pmvs, colmap, strecha or opensfm");
}

std::string ToString(BlockFormat format) {
  switch (format) {
    case BlockFormat::kAuto:
      return "auto";
    case BlockFormat::kYaml:
      return "yaml";
    case BlockFormat::kPmvs:
      return "pmvs";
    case BlockFormat::kColmap:
      return "colmap";
    case BlockFormat::kStrecha:
      return "strecha";
    case BlockFormat::kOpenSfm:
      return "opensfm";
  }
  return "?";
}

std::string BlockReadOptions::Problem() const {
  if (!image_dir.empty() && !fs::is_directory(image_dir)) {
    return "image_dir " + image_dir.string() + " to be a folder";
  }
  if (ground_height && !std::isfinite(*ground_height)) {
    std::ostringstream s;
    s << "a finite ground height (ground_height = " << *ground_height << ")";
    return s.str();
  }
  if (enu_origin) {
    const std::string p = AsGeoReference(*enu_origin).Problem();
    if (!p.empty()) return "an ENU origin with " + p;
  }
  return "";
}

bool BlockReadOptions::Check() const {
  const std::string p = Problem();
  if (!p.empty()) std::cerr << "BlockReadOptions: expected " << p << "\n";
  return p.empty();
}

BlockFormat DetectBlockFormat(const fs::path& path) {
  if (!fs::exists(path)) throw Error(path.string() + ": block not found (no such file or folder)");
  if (!fs::is_directory(path)) RequireRegularFile(path);  // a FIFO would block the reader
  if (fs::is_regular_file(path)) {
    const std::string ext = path.extension().string();
    const std::string name = path.filename().string();
    if (ext == ".yaml" || ext == ".yml") return BlockFormat::kYaml;
    if (ext == ".json") return BlockFormat::kOpenSfm;
    if (ext == ".camera") return BlockFormat::kStrecha;
    if (name == "cameras.txt" || name == "images.txt" || name == "cameras.bin" ||
        name == "images.bin") {
      return BlockFormat::kColmap;
    }
    throw Error(path.string() +
                ": unknown block file (expected a .yaml block, an OpenSfM .json, a Strecha "
                ".camera, or COLMAP cameras.txt/images.txt or .bin; or give --format)");
  }
  if (fs::is_regular_file(path / "block.yaml")) return BlockFormat::kYaml;
  if (fs::is_regular_file(path / "reconstruction.json") ||
      fs::is_regular_file(path / "opensfm" / "reconstruction.json")) {
    return BlockFormat::kOpenSfm;
  }
  for (const fs::path& sub : {fs::path(), fs::path("sparse"), fs::path("sparse") / "0"}) {
    if ((fs::is_regular_file(path / sub / "cameras.txt") &&
         fs::is_regular_file(path / sub / "images.txt")) ||
        (fs::is_regular_file(path / sub / "cameras.bin") &&
         fs::is_regular_file(path / sub / "images.bin"))) {
      return BlockFormat::kColmap;
    }
  }
  if (IsPmvsFolder(path)) return BlockFormat::kPmvs;
  if (HasCameraFiles(path) || HasCameraFiles(path / "gt_dense_cameras")) {
    return BlockFormat::kStrecha;
  }
  throw Error(path.string() +
              ": no block found in folder (looked for block.yaml, reconstruction.json, "
              "cameras.txt + images.txt (or .bin), txt/NNNNNNNN.txt, *.camera; or give --format)");
}

namespace {

Block ReadBlockAs(const fs::path& path, BlockFormat format, const BlockReadOptions& options) {
  Block block;
  switch (format) {
    case BlockFormat::kYaml:
      block = ReadYamlBlock(path, options);
      break;
    case BlockFormat::kPmvs:
      block = ReadPmvsBlock(path, options);
      break;
    case BlockFormat::kColmap:
      block = ReadColmapBlock(path, options);
      break;
    case BlockFormat::kStrecha:
      block = ReadStrechaBlock(path, options);
      break;
    case BlockFormat::kOpenSfm:
      block = ReadOpenSfmBlock(path, options);
      break;
    case BlockFormat::kAuto:
      break;
  }
  return block;
}

}  // namespace

Block ReadBlock(const fs::path& path, const BlockReadOptions& options) {
  if (const std::string p = options.Problem(); !p.empty()) {
    throw Error("block read options: expected " + p);
  }
  const BlockFormat format =
      options.format == BlockFormat::kAuto ? DetectBlockFormat(path) : options.format;
  Block block;
  try {
    block = ReadBlockAs(path, format, options);
  } catch (const fs::filesystem_error& e) {
    // A path the system refuses (too long, a loop of links) as one line that
    // names the block; the path itself may be kilobytes of a hostile file.
    std::string what = e.path1().string();
    if (what.size() > 120) what = what.substr(0, 120) + "...";
    throw Error(path.string() + ": " + e.code().message() + ": " + what);
  }
  block.source = path;
  if (options.ground_height) block.ground_height = options.ground_height;
  block.format = ToString(format);
  if (block.images.empty()) throw Error(path.string() + ": block has no images");
  // Two images on one file (names that differ only in the extension the
  // reader adds, a.jpg and a) would match a picture with itself.
  std::map<fs::path, const BlockImage*> by_file;
  for (const BlockImage& im : block.images) {
    const auto [it, fresh] = by_file.emplace(im.path.lexically_normal(), &im);
    if (!fresh) {
      throw Error(im.path.string() + ": the file of both image '" + it->second->name +
                  "' and image '" + im.name + "' (expected one file per image)");
    }
  }
  for (const BlockImage& im : block.images) {
    im.camera.intrinsics().Validate("image '" + im.name + "'");
    if (!im.camera.center().allFinite() || !im.camera.rotation().allFinite()) {
      throw Error("image '" + im.name + "': non-finite exterior orientation");
    }
    if (options.check_image_sizes) {
      const ImageSize size = ReadImageSize(im.path);
      if (size.width != im.camera.width() || size.height != im.camera.height()) {
        throw Error(im.path.string() + ": image is " + std::to_string(size.width) + "x" +
                    std::to_string(size.height) + " px, its camera expects " +
                    std::to_string(im.camera.width()) + "x" + std::to_string(im.camera.height()));
      }
    }
  }
  ApplyFrame(options, &block);
  block.origin = ChooseLocalOrigin(block.images);
  return block;
}

}  // namespace sapmvs

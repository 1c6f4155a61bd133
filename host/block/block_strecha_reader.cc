// Strecha .camera files (EPFL multi-view benchmark): per image `NAME.camera`
//   K (3 rows) / radial distortion (k1 k2 k3) / R (3 rows, camera-to-world,
//   columns = camera axes in world) / C (1 row) / W H
// so that P = K [R^T | -R^T C] with the OpenCV camera frame.

#include <algorithm>
#include <map>
#include <sstream>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

Eigen::Vector3d Row3(TextLines& lines, const std::string& what) {
  std::vector<std::string> t;
  if (!lines.Next(&t)) throw lines.Fail("unexpected end of file, expected " + what);
  lines.ExpectCount(t, 3, what);
  return {lines.Double(t[0], what), lines.Double(t[1], what), lines.Double(t[2], what)};
}

Camera ReadCameraFile(const fs::path& path, std::string* name) {
  TextLines lines(path);
  Eigen::Matrix3d k, r;
  for (int i = 0; i < 3; ++i) k.row(i) = Row3(lines, "K row " + std::to_string(i + 1)).transpose();
  if (k(1, 0) != 0 || k(2, 0) != 0 || k(2, 1) != 0 || k(2, 2) != 1) {
    throw InputError(path.string(), 3, "expected K = [fx s cx; 0 fy cy; 0 0 1]");
  }
  const Eigen::Vector3d dist = Row3(lines, "radial distortion k1 k2 k3");
  for (int i = 0; i < 3; ++i) r.row(i) = Row3(lines, "R row " + std::to_string(i + 1)).transpose();
  const int r_line = lines.line();
  const Eigen::Vector3d c = Row3(lines, "camera centre C x y z");
  std::vector<std::string> t;
  if (!lines.Next(&t)) throw lines.Fail("unexpected end of file, expected image size W H");
  lines.ExpectCount(t, 2, "image size W H");
  const int w = lines.Int(t[0], "width"), h = lines.Int(t[1], "height");
  if (w <= 0 || h <= 0) throw lines.Fail("expected a positive image size W H");
  if (lines.Next(&t)) throw lines.Fail("unexpected extra content after W H");
  if (!(k(0, 0) > 0 && k(1, 1) > 0)) {
    std::ostringstream s;
    s << "expected positive focal lengths in K, got fx = " << k(0, 0) << ", fy = " << k(1, 1);
    throw InputError(path.string(), k(0, 0) > 0 ? 2 : 1, s.str());
  }
  if (std::abs(k(0, 1)) > 1e-3 * k(0, 0)) {
    std::ostringstream s;
    s << "skew " << k(0, 1) << " in K is not supported (expected K = [fx 0 cx; 0 fy cy; 0 0 1])";
    throw InputError(path.string(), 1, s.str());
  }
  Intrinsics in = Intrinsics::FromPixels(k(0, 0), k(1, 1), k(0, 2), k(1, 2), w, h);
  in.distortion.k1 = dist[0];
  in.distortion.k2 = dist[1];
  in.distortion.k3 = dist[2];
  Eigen::Matrix3d r_cw;
  try {
    r_cw = CheckedRotation(r, "R");
  } catch (const Error& e) {
    throw InputError(path.string(), r_line, e.what());
  }
  // "0000.jpg.camera" describes image "0000.jpg".
  *name = path.stem().string();
  return Camera(in, r_cw.transpose(), c);
}

}  // namespace

Block ReadStrechaBlock(const fs::path& given, const BlockReadOptions& options) {
  fs::path camera_dir = given;
  if (fs::is_regular_file(given))
    camera_dir = given.parent_path();
  else if (fs::is_directory(given / "gt_dense_cameras"))
    camera_dir = given / "gt_dense_cameras";
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(camera_dir)) {
    if (e.path().extension() == ".camera") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw Error(camera_dir.string() + ": no .camera files");

  fs::path image_dir = options.image_dir;
  if (image_dir.empty()) {
    for (const fs::path& cand : {camera_dir.parent_path() / "images", camera_dir}) {
      if (fs::is_directory(cand) && !FindImageFile(cand, files.front().stem().string()).empty()) {
        image_dir = cand;
        break;
      }
    }
    if (image_dir.empty()) image_dir = camera_dir.parent_path() / "images";
  }
  Block block;
  block.frame_note = "Strecha ground-truth frame (metres)";
  std::map<fs::path, fs::path> described_by;  // image file -> its .camera file
  for (const fs::path& file : files) {
    BlockImage im;
    im.camera = ReadCameraFile(file, &im.name);
    im.camera_name = "K";
    im.path = FindImageFile(image_dir, im.name);
    if (im.path.empty()) {
      throw InputError(file.string(), 0, "no image '" + im.name + "' in " + image_dir.string());
    }
    if (const auto [it, fresh] = described_by.emplace(im.path, file); !fresh) {
      throw InputError(file.string(), 0,
                       "image " + im.path.filename().string() + " is already described by " +
                           it->second.filename().string() +
                           " (expected one .camera file per image)");
    }
    block.images.push_back(std::move(im));
  }
  return block;
}

}  // namespace sapmvs

// COLMAP's text model: cameras.txt, images.txt and (optionally) points3D.txt.
//   cameras.txt  CAMERA_ID MODEL WIDTH HEIGHT PARAMS...
//   images.txt   IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, then one line
//                of 2D points (possibly empty) per image
//   x_cam = R(q) X + t, OpenCV camera frame. COLMAP puts pixel centres at
//   half-integers (the image corner is 0, 0), so 0.5 is taken off cx and cy.
// A project `sapmvs export` wrote is in the block's local frame; its side file
// (export_frame.h), at the project's root, puts it back into the world frame.

#include <Eigen/Geometry>
#include <iostream>
#include <map>

#include "block/colmap_camera.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/export_frame.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace fs = std::filesystem;

const std::vector<ColmapModel>& ColmapModels() {
  static const std::vector<ColmapModel> models = {
      {"SIMPLE_PINHOLE", 3, "f cx cy"},         {"PINHOLE", 4, "fx fy cx cy"},
      {"SIMPLE_RADIAL", 4, "f cx cy k"},        {"RADIAL", 5, "f cx cy k1 k2"},
      {"OPENCV", 8, "fx fy cx cy k1 k2 p1 p2"},
  };
  return models;
}

Intrinsics ColmapIntrinsics(const ColmapModel& model, int w, int h, const std::vector<double>& p) {
  Intrinsics k;
  const std::string m = model.name;
  if (m == "PINHOLE" || m == "OPENCV") {
    k = Intrinsics::FromPixels(p[0], p[1], p[2] - 0.5, p[3] - 0.5, w, h);
  } else {
    k = Intrinsics::FromPixels(p[0], p[0], p[1] - 0.5, p[2] - 0.5, w, h);
  }
  if (m == "SIMPLE_RADIAL") k.distortion.k1 = p[3];
  if (m == "RADIAL") {
    k.distortion.k1 = p[3];
    k.distortion.k2 = p[4];
  }
  if (m == "OPENCV") {
    k.distortion.k1 = p[4];
    k.distortion.k2 = p[5];
    k.distortion.p1 = p[6];
    k.distortion.p2 = p[7];
  }
  return k;
}

namespace {

Intrinsics ParseCamera(const TextLines& lines, const std::vector<std::string>& t) {
  lines.ExpectCount(t, 4, "CAMERA_ID MODEL WIDTH HEIGHT PARAMS...", true);
  const ColmapModel* model = nullptr;
  for (const ColmapModel& m : ColmapModels()) {
    if (t[1] == m.name) model = &m;
  }
  if (!model) {
    throw lines.Fail("unsupported camera model '" + t[1] +
                     "': expected SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL or OPENCV");
  }
  const std::string layout =
      std::string("CAMERA_ID ") + model->name + " WIDTH HEIGHT " + model->layout;
  lines.ExpectCount(t, 4 + model->num_params, layout);
  const int w = lines.Int(t[2], "WIDTH"), h = lines.Int(t[3], "HEIGHT");
  if (w <= 0 || h <= 0) throw lines.Fail("expected a positive WIDTH and HEIGHT");
  std::vector<double> p;
  for (int i = 0; i < model->num_params; ++i)
    p.push_back(lines.Double(t[4 + i], "camera parameter " + std::to_string(i + 1)));
  const Intrinsics k = ColmapIntrinsics(*model, w, h, p);
  if (!(k.fx > 0 && k.fy > 0)) throw lines.Fail("expected a positive focal length");
  return k;
}

fs::path ModelDir(const fs::path& given) {
  if (fs::is_regular_file(given)) return given.parent_path();
  for (const fs::path& dir : {given, given / "sparse", given / "sparse" / "0"}) {
    if (fs::is_regular_file(dir / "cameras.txt") || fs::is_regular_file(dir / "cameras.bin"))
      return dir;
  }
  return given;
}

// COLMAP writes the binary model by default and the text one on export; when
// a folder has both, the binary one is read (it is what COLMAP itself loads)
// and a note says so. A file given by name chooses its own kind.
bool UseBinaryModel(const fs::path& given, const fs::path& dir) {
  if (fs::is_regular_file(given)) return given.extension() == ".bin";
  const bool bin =
      fs::is_regular_file(dir / "cameras.bin") && fs::is_regular_file(dir / "images.bin");
  if (bin && fs::is_regular_file(dir / "cameras.txt")) {
    std::cerr << "note: " << dir.string()
              << " has both a binary (.bin) and a text (.txt) COLMAP model; reading the binary "
                 "one\n";
  }
  return bin;
}

// The export's root holds sparse/0 (or is the model folder itself).
fs::path ExportRoot(const fs::path& model_dir) {
  // Absolute, so that a relative model folder's parents are real folders.
  fs::path dir = fs::absolute(model_dir).lexically_normal();
  if (!dir.has_filename()) dir = dir.parent_path();  // a trailing slash
  for (const fs::path& cand : {dir, dir.parent_path(), dir.parent_path().parent_path()}) {
    if (fs::is_regular_file(cand / kExportFrameFile) ||
        fs::is_regular_file(cand / kExportMarkerFile)) {
      return cand;
    }
  }
  return {};
}

}  // namespace

Block ReadColmapBlock(const fs::path& given, const BlockReadOptions& options) {
  const fs::path dir = ModelDir(given);
  const fs::path export_root = ExportRoot(dir);
  const std::optional<ExportFrame> frame =
      export_root.empty() ? std::nullopt : ReadExportFrame(export_root);
  const bool binary = UseBinaryModel(given, dir);
  std::map<int, Intrinsics> cameras;
  if (!binary) {
    TextLines lines(dir / "cameras.txt");
    std::vector<std::string> t;
    while (lines.Next(&t)) {
      const int id = lines.Int(t[0], "CAMERA_ID");
      if (cameras.count(id)) throw lines.Fail("camera " + t[0] + " defined twice");
      cameras[id] = ParseCamera(lines, t);
    }
  }
  if (!binary && cameras.empty()) throw InputError((dir / "cameras.txt").string(), 0, "no cameras");

  fs::path image_dir = options.image_dir;
  if (image_dir.empty()) {
    // COLMAP projects keep images/ beside sparse/ (model in sparse/ or sparse/N).
    for (const fs::path& cand : {dir / "images", dir.parent_path() / "images",
                                 dir.parent_path().parent_path() / "images"}) {
      if (fs::is_directory(cand)) {
        image_dir = cand;
        break;
      }
    }
    if (image_dir.empty()) image_dir = dir / "images";
  }

  Block block;
  if (binary) {
    block = ReadColmapBinaryModel(dir, image_dir);
    if (frame) ApplyExportFrame(*frame, export_root, "colmap", &block);
    return block;
  }
  block.frame_note = "COLMAP model frame";
  TextLines lines(dir / "images.txt");
  std::string line;
  std::map<std::string, int> first_line;  // image name -> line in images.txt
  while (lines.NextRaw(&line)) {
    const std::vector<std::string> t = SplitWhitespace(line);
    if (t.empty()) continue;
    lines.ExpectCount(t, 10, "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME", true);
    double v[7];
    for (int i = 0; i < 7; ++i) v[i] = lines.Double(t[1 + i], i < 4 ? "quaternion" : "translation");
    const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (std::abs(q.norm() - 1) > 1e-3) {
      throw lines.Fail("quaternion QW QX QY QZ has norm " + std::to_string(q.norm()) +
                       ", expected 1");
    }
    const int cam_id = lines.Int(t[8], "CAMERA_ID");
    const auto cam = cameras.find(cam_id);
    if (cam == cameras.end()) throw lines.Fail("unknown CAMERA_ID " + t[8]);
    BlockImage im;
    im.name = t[9];
    for (size_t i = 10; i < t.size(); ++i) im.name += " " + t[i];
    if (const auto [it, fresh] = first_line.emplace(im.name, lines.line()); !fresh) {
      throw lines.Fail("image '" + im.name + "' listed twice (first on line " +
                       std::to_string(it->second) + ")");
    }
    im.camera_name = "camera " + t[8];
    const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
    const Eigen::Vector3d tr(v[4], v[5], v[6]);
    im.camera = Camera(cam->second, r, -r.transpose() * tr);
    im.path = FindImageFile(image_dir, im.name);
    if (im.path.empty()) throw lines.Fail("no image '" + im.name + "' in " + image_dir.string());
    block.images.push_back(std::move(im));
    // The 2D points line follows every image line, empty or not.
    lines.NextRaw(&line);
  }

  if (fs::is_regular_file(dir / "points3D.txt")) {
    TextLines pts(dir / "points3D.txt");
    std::vector<std::string> t;
    while (pts.Next(&t)) {
      pts.ExpectCount(t, 8, "POINT3D_ID X Y Z R G B ERROR TRACK...", true);
      block.sparse_points.emplace_back(pts.Double(t[1], "X"), pts.Double(t[2], "Y"),
                                       pts.Double(t[3], "Z"));
    }
  }
  if (frame) ApplyExportFrame(*frame, export_root, "colmap", &block);
  return block;
}

}  // namespace sapmvs

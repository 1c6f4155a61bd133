// The native block.yaml reader. Layout (paths relative to the yaml file):
//
//   crs: "EPSG:32651"            # optional, kept and written into outputs
//   ground_height: 300           # optional, mean ground height (block units)
//   dem: dem.tif                 # optional, elevation raster in the block's frame
//   camera:                      # or `cameras:`, a list of these with `name:`
//     width: 640                 # px
//     height: 1152               # px
//     focal_mm: 120              # with pixel_um: 9.0 or sensor_mm: [w, h]
//     principal_offset_mm: [0, 0]  # optional; photogrammetric x right, y up
//     # or, in pixels: fx fy cx cy ((0, 0) = centre of the top-left pixel)
//     distortion: {k1: 0, k2: 0, k3: 0, p1: 0, p2: 0}  # optional, OpenCV model
//   images: images/              # a folder (matched by name), or a list of files
//   orientation:
//     file: orientation.txt      # `name X Y Z a1 a2 a3 [camera]` per line
//     format: plain              # or metashape | pix4d (orientation_export.h);
//                                #   detected from the file when not given
//     type: angles               # angles | rotation | projection
//     angles: omega-phi-kappa    # or phi-omega-kappa (type: angles)
//     units: deg                 # deg | gon | rad (type: angles)
//     rotation: camera-to-world  # or world-to-camera-opencv (type: rotation:
//                                #   `name X Y Z r11 .. r33`)
//                                # type: projection: `name P11 .. P34`

#include <yaml-cpp/yaml.h>

#include <map>

#include "block/orientation_export.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/input_file.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

class YamlFile {
 public:
  explicit YamlFile(const fs::path& path) : path_(path.string()) {}

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& message) const {
    throw InputError(path_, node.IsDefined() ? node.Mark().line + 1 : 0, message);
  }

  YAML::Node Required(const YAML::Node& map, const std::string& key,
                      const std::string& where) const {
    // Subscripting a scalar throws yaml-cpp's own exception, not ours.
    if (!map.IsMap()) Fail(map, "expected a mapping for " + where + " (with '" + key + "')");
    YAML::Node n = map[key];
    if (!n.IsDefined() || n.IsNull()) {
      throw InputError(path_, map.Mark().line + 1, "missing key '" + key + "' in " + where);
    }
    return n;
  }

  template <typename T>
  T As(const YAML::Node& node, const std::string& what) const {
    try {
      return node.as<T>();
    } catch (const YAML::Exception&) {
      Fail(node, "expected " + what);
    }
  }

  double Number(const YAML::Node& node, const std::string& what) const {
    const double v = As<double>(node, "a number for " + what);
    if (!std::isfinite(v)) Fail(node, "expected a finite number for " + what);
    return v;
  }

  Eigen::Vector2d Pair(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() != 2) Fail(node, "expected [a, b] for " + what);
    return {Number(node[0], what), Number(node[1], what)};
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

Intrinsics ReadCamera(const YamlFile& f, const YAML::Node& node) {
  if (!node.IsMap()) f.Fail(node, "expected a camera mapping");
  const int width = f.As<int>(f.Required(node, "width", "camera"), "an integer width (px)");
  const int height = f.As<int>(f.Required(node, "height", "camera"), "an integer height (px)");
  if (width <= 0 || height <= 0) f.Fail(node["width"], "expected positive width and height");
  Intrinsics k;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  if (node["principal_offset_mm"]) {
    offset = f.Pair(node["principal_offset_mm"], "principal_offset_mm");
  }
  try {
    if (node["fx"]) {
      k = Intrinsics::FromPixels(f.Number(node["fx"], "fx"),
                                 f.Number(f.Required(node, "fy", "camera"), "fy"),
                                 f.Number(f.Required(node, "cx", "camera"), "cx"),
                                 f.Number(f.Required(node, "cy", "camera"), "cy"), width, height);
      k.Validate("camera");
    } else {
      const double focal =
          f.Number(f.Required(node, "focal_mm", "camera (or give fx fy cx cy)"), "focal_mm");
      if (node["pixel_um"]) {
        k = Intrinsics::FromFocalAndPixel(focal, f.Number(node["pixel_um"], "pixel_um"), width,
                                          height, offset);
      } else if (node["sensor_mm"]) {
        const Eigen::Vector2d s = f.Pair(node["sensor_mm"], "sensor_mm");
        k = Intrinsics::FromFocalAndSensor(focal, s.x(), s.y(), width, height, offset);
      } else {
        f.Fail(node, "camera with focal_mm needs pixel_um or sensor_mm");
      }
    }
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    f.Fail(node, e.what());
  }
  if (const YAML::Node d = node["distortion"]) {
    if (!d.IsMap()) f.Fail(d, "expected distortion: {k1, k2, k3, p1, p2}");
    for (const auto& kv : d) {
      const std::string key = f.As<std::string>(kv.first, "a distortion key");
      const double v = f.Number(kv.second, "distortion " + key);
      if (key == "k1")
        k.distortion.k1 = v;
      else if (key == "k2")
        k.distortion.k2 = v;
      else if (key == "k3")
        k.distortion.k3 = v;
      else if (key == "p1")
        k.distortion.p1 = v;
      else if (key == "p2")
        k.distortion.p2 = v;
      else
        f.Fail(kv.first, "unknown distortion term '" + key + "': expected k1 k2 k3 p1 p2");
    }
  }
  return k;
}

// Image files by orientation name: from a folder, or from an explicit list.
class ImageLocator {
 public:
  ImageLocator(const YamlFile& f, const YAML::Node& node, const fs::path& base,
               const fs::path& override_dir) {
    if (!override_dir.empty()) {
      folder_ = override_dir;
    } else if (node.IsScalar()) {
      folder_ = base / f.As<std::string>(node, "an image folder");
      // The error_code form: a name too long for the system is "not found"
      // here, where the throwing form escaped as a filesystem_error (fuzzing).
      std::error_code ec;
      if (!fs::is_directory(folder_, ec)) {
        f.Fail(node, "image folder not found: " + folder_.string() +
                         (ec ? " (" + ec.message() + ")" : ""));
      }
    } else if (node.IsSequence()) {
      for (const auto& item : node) {
        const fs::path p = base / f.As<std::string>(item, "an image file name");
        by_stem_[p.stem().string()] = p;
        by_stem_[p.filename().string()] = p;
      }
    } else {
      f.Fail(node, "expected images: a folder or a list of files");
    }
  }

  // `file` and `line` name where the orientation lists `name`.
  fs::path Find(const std::string& name, const std::string& file, int line) const {
    if (!folder_.empty()) {
      fs::path p = FindImageFile(folder_, name);
      if (p.empty())
        throw InputError(file, line, "no image for '" + name + "' in " + folder_.string());
      return p;
    }
    auto it = by_stem_.find(name);
    if (it == by_stem_.end()) it = by_stem_.find(fs::path(name).stem().string());
    if (it == by_stem_.end())
      throw InputError(file, line, "image '" + name + "' is not in the images list");
    return it->second;
  }

 private:
  fs::path folder_;
  std::map<std::string, fs::path> by_stem_;
};

// A value parsed by `fn` (which throws sapmvs::Error); its errors point at
// the value's line.
template <typename Fn>
auto ParseValue(const YamlFile& f, const YAML::Node& node, Fn fn) {
  const std::string text = f.As<std::string>(node, "a string");
  try {
    return fn(text);
  } catch (const InputError&) {
    throw;
  } catch (const Error& e) {
    f.Fail(node, e.what());
  }
}

// Metashape and Pix4D fix the angles' order and unit: keys saying otherwise
// contradict the file instead of choosing for it.
void CheckExportKeys(const YamlFile& f, const YAML::Node& ori, const std::string& what) {
  const std::string fixed = "the orientation is " + what + " (omega-phi-kappa in degrees)";
  if (ori["type"] && f.As<std::string>(ori["type"], "a type") != "angles")
    f.Fail(ori["type"], fixed + ": expected type: angles, or no type");
  if (ori["angles"] && ParseValue(f, ori["angles"], ParseAngleOrder) != AngleOrder::kOmegaPhiKappa)
    f.Fail(ori["angles"], fixed + ": expected angles: omega-phi-kappa, or no angles");
  if (ori["units"] && ParseValue(f, ori["units"], ParseAngleUnit) != AngleUnit::kDegree)
    f.Fail(ori["units"], fixed + ": expected units: deg, or no units");
}

// The cameras of a Metashape or Pix4D export, all with the block's one camera.
void AddExportedImages(const YamlFile& f, const YAML::Node& ori, OrientationFormat format,
                       const fs::path& file, const Intrinsics* camera,
                       const std::string& camera_name, const ImageLocator& images, Block* block) {
  const std::string what =
      format == OrientationFormat::kMetashape ? "a Metashape export" : "a Pix4D export";
  CheckExportKeys(f, ori, what);
  if (camera == nullptr) {
    f.Fail(ori, file.filename().string() + " is " + what +
                    ", which names no camera per image: expected one camera in block.yaml");
  }
  const std::vector<ExportedPose> poses =
      format == OrientationFormat::kMetashape ? ReadMetashapeOpk(file) : ReadPix4dExternal(file);
  for (const ExportedPose& pose : poses) {
    BlockImage im;
    im.name = pose.name;
    im.camera_name = camera_name;
    im.path = images.Find(pose.name, file.string(), pose.line);
    im.camera = Camera::FromCameraToWorld(*camera, pose.center, pose.camera_to_world);
    block->images.push_back(std::move(im));
  }
}

}  // namespace

Block ReadYamlBlock(const fs::path& given, const BlockReadOptions& options) {
  const fs::path path = fs::is_directory(given) ? given / "block.yaml" : given;
  const YamlFile f(path);
  RequireRegularFile(path);
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::ParserException& e) {
    throw InputError(path.string(), e.mark.line + 1, "not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(path.string(), 1, "expected a YAML mapping (block file)");
  const fs::path base = path.parent_path();

  Block block;
  if (root["crs"] && !root["crs"].IsNull())
    block.crs = f.As<std::string>(root["crs"], "a CRS string");
  if (root["ground_height"]) block.ground_height = f.Number(root["ground_height"], "ground_height");
  if (root["dem"]) {
    block.dem = base / f.As<std::string>(root["dem"], "a DEM file name");
    if (!fs::is_regular_file(block.dem))
      f.Fail(root["dem"], "DEM not found: " + block.dem.string());
  }

  std::map<std::string, Intrinsics> cameras;
  std::string single_camera;
  if (root["camera"]) {
    single_camera = root["camera"].IsMap() && root["camera"]["name"]
                        ? f.As<std::string>(root["camera"]["name"], "a name")
                        : "camera";
    cameras[single_camera] = ReadCamera(f, root["camera"]);
  } else if (root["cameras"] && root["cameras"].IsSequence()) {
    for (const auto& c : root["cameras"]) {
      const std::string name = f.As<std::string>(f.Required(c, "name", "camera"), "a camera name");
      cameras[name] = ReadCamera(f, c);
    }
    if (cameras.size() == 1) single_camera = cameras.begin()->first;
  } else {
    throw InputError(path.string(), 1, "missing 'camera' (a mapping) or 'cameras' (a list)");
  }

  const ImageLocator images(f, f.Required(root, "images", "block"), base, options.image_dir);

  const YAML::Node ori = f.Required(root, "orientation", "block");
  const fs::path ori_file =
      base / f.As<std::string>(f.Required(ori, "file", "orientation"), "an orientation file name");
  const std::string type = ori["type"] ? f.As<std::string>(ori["type"], "a type") : "angles";
  AngleOrder order = AngleOrder::kOmegaPhiKappa;
  AngleUnit unit = AngleUnit::kDegree;
  bool camera_to_world = true;
  size_t numbers = 6;
  std::string layout = "name X Y Z a1 a2 a3";
  auto parse = [&f](const YAML::Node& node, auto fn) { return ParseValue(f, node, fn); };
  OrientationFormat format =
      ori["format"] ? parse(ori["format"], ParseOrientationFormat) : OrientationFormat::kAuto;
  if (format == OrientationFormat::kAuto) format = DetectOrientationFormat(ori_file);
  if (format == OrientationFormat::kMetashape || format == OrientationFormat::kPix4d) {
    const auto cam = cameras.find(single_camera);
    AddExportedImages(f, ori, format, ori_file, cam == cameras.end() ? nullptr : &cam->second,
                      single_camera, images, &block);
    return block;
  }
  if (type == "angles") {
    order = parse(f.Required(ori, "angles", "orientation"), ParseAngleOrder);
    unit = parse(f.Required(ori, "units", "orientation"), ParseAngleUnit);
  } else if (type == "rotation") {
    const std::string conv =
        f.As<std::string>(f.Required(ori, "rotation", "orientation"), "a name");
    if (conv == "world-to-camera-opencv") {
      camera_to_world = false;
    } else if (conv != "camera-to-world") {
      f.Fail(ori["rotation"],
             "unknown rotation '" + conv + "': expected camera-to-world or world-to-camera-opencv");
    }
    numbers = 12;
    layout = "name X Y Z r11 r12 r13 r21 r22 r23 r31 r32 r33";
  } else if (type == "projection") {
    numbers = 12;
    layout = "name P11 P12 P13 P14 P21 ... P34";
  } else {
    f.Fail(ori["type"],
           "unknown orientation type '" + type + "': expected angles, rotation or projection");
  }

  TextLines lines(ori_file);
  std::vector<std::string> t;
  if (single_camera.empty()) layout += " camera";
  while (lines.Next(&t)) {
    lines.ExpectCount(t, numbers + 1 + (single_camera.empty() ? 1 : 0), layout);
    double v[12];
    for (size_t i = 0; i < numbers; ++i)
      v[i] = lines.Double(t[i + 1], "field " + std::to_string(i + 2));
    BlockImage im;
    im.name = t[0];
    im.camera_name = single_camera.empty() ? t.back() : single_camera;
    const auto cam = cameras.find(im.camera_name);
    if (cam == cameras.end()) throw lines.Fail("unknown camera '" + im.camera_name + "'");
    if (block.FindImage(im.name) >= 0) throw lines.Fail("image '" + im.name + "' listed twice");
    im.path = images.Find(im.name, lines.file(), lines.line());
    try {
      const Eigen::Vector3d c(v[0], v[1], v[2]);
      if (type == "angles") {
        im.camera = Camera::FromAngles(cam->second, c, v[3], v[4], v[5], order, unit);
      } else if (type == "rotation") {
        Eigen::Matrix3d r;
        r << v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11];
        r = CheckedRotation(r, "rotation");
        im.camera = camera_to_world ? Camera::FromCameraToWorld(cam->second, c, r)
                                    : Camera(cam->second, r, c);
      } else {
        Eigen::Matrix<double, 3, 4> p;
        for (int i = 0; i < 12; ++i) p(i / 4, i % 4) = v[i];
        Camera pc = Camera::FromProjectionMatrix(p, cam->second.width, cam->second.height);
        Intrinsics k = pc.intrinsics();
        k.distortion = cam->second.distortion;
        im.camera = pc.WithIntrinsics(k);
      }
    } catch (const InputError&) {
      throw;
    } catch (const Error& e) {
      throw lines.Fail(e.what());
    }
    block.images.push_back(std::move(im));
  }
  if (block.images.empty()) throw InputError(ori_file.string(), 0, "no orientation lines");
  return block;
}

}  // namespace sapmvs

// OpenSfM reconstruction.json (also what OpenDroneMap writes under opensfm/).
// Cameras: focal and principal point normalised by max(width, height), the
// principal point as an offset from the image centre. Shots: `rotation` is an
// angle-axis world-to-camera rotation, x_cam = R X + translation, OpenCV frame.
// The world frame is topocentric ENU about the reference point given by the
// reconstruction's `reference_lla` (newer OpenSfM) or by reference_lla.json
// beside it (older OpenSfM, OpenDroneMap); with one, the block is moved into
// that point's UTM zone (topocentric_to_utm.h), without one it stays in the
// reconstruction's own frame.

#include <Eigen/Geometry>
#include <algorithm>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "block/topocentric_to_utm.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "util/input_file.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

using json = nlohmann::json;

// nlohmann's what() starts with "[json.exception.parse_error.101] "; the user
// needs only the rest.
std::string JsonDetail(const json::exception& e) {
  std::string s = e.what();
  if (!s.empty() && s[0] == '[') {
    const size_t end = s.find("] ");
    if (end != std::string::npos) s = s.substr(end + 2);
  }
  return s;
}

// Thrown by the parser callback at a key an object already holds: nlohmann
// would keep one of the two silently, and for shots that drops an image.
struct DuplicateKey {
  std::string key;
};

// JSON values carry no line numbers; errors name the JSON path and the line
// where the nearest enclosing key first appears in the file.
class JsonFile {
 public:
  explicit JsonFile(const fs::path& path) : path_(path.string()) {
    std::ifstream in = OpenInputFile(path);
    std::stringstream ss;
    ss << in.rdbuf();
    text_ = ss.str();
    std::vector<std::set<std::string>> keys;  // per open object
    const json::parser_callback_t check_keys = [&keys](int, json::parse_event_t event,
                                                       json& parsed) {
      if (event == json::parse_event_t::object_start) {
        keys.emplace_back();
      } else if (event == json::parse_event_t::object_end) {
        keys.pop_back();
      } else if (event == json::parse_event_t::key && !keys.empty()) {
        if (!keys.back().insert(parsed.get<std::string>()).second) {
          throw DuplicateKey{parsed.get<std::string>()};
        }
      }
      return true;
    };
    try {
      root_ = json::parse(text_, check_keys);
    } catch (const DuplicateKey& d) {
      const std::string quoted = "\"" + d.key + "\"";
      const size_t first = text_.find(quoted);
      const size_t second = text_.find(quoted, first + 1);
      throw InputError(path_, second == std::string::npos ? 0 : LineAt(second + 1),
                       "key '" + d.key + "' appears twice in one object (first on line " +
                           std::to_string(LineAt(first + 1)) + "); expected unique names");
    } catch (const json::parse_error& e) {
      // "parse error at line L, column C: what": keep the column and what.
      std::string detail = JsonDetail(e);
      const size_t column = detail.find("column ");
      if (column != std::string::npos) detail = "at " + detail.substr(column);
      throw InputError(path_, LineAt(e.byte), "not valid JSON " + detail);
    } catch (const json::out_of_range& e) {
      // A number beyond double's range (1e999); the message quotes it.
      const std::string detail = JsonDetail(e);
      const size_t open = detail.find('\''), close = detail.rfind('\'');
      const std::string number = open != std::string::npos && close > open
                                     ? detail.substr(open + 1, close - open - 1)
                                     : "";
      const size_t at = number.empty() ? std::string::npos : text_.find(number);
      throw InputError(path_, at == std::string::npos ? 0 : LineAt(at + 1),
                       "number " + number + " is out of range (expected a finite number)");
    }
  }

  const json& root() const { return root_; }
  const std::string& path() const { return path_; }
  // The line of the first `"key"` in the file, or 0.
  int LineOf(const std::string& key) const {
    const size_t pos = text_.find("\"" + key + "\"");
    return pos == std::string::npos ? 0 : LineAt(pos + 1);
  }

  [[noreturn]] void Fail(const std::string& key, const std::string& json_path,
                         const std::string& message) const {
    const size_t pos = text_.find("\"" + key + "\"");
    throw InputError(path_, pos == std::string::npos ? 0 : LineAt(pos + 1),
                     json_path + ": " + message);
  }

  double Number(const json& obj, const std::string& key, const std::string& where,
                const std::string& anchor) const {
    if (!obj.is_object() || !obj.contains(key)) Fail(anchor, where, "missing number '" + key + "'");
    const json& v = obj[key];
    if (!v.is_number()) Fail(anchor, where + "/" + key, "expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) Fail(anchor, where + "/" + key, "expected a finite number");
    return d;
  }

  Eigen::Vector3d Vector3(const json& obj, const std::string& key, const std::string& where,
                          const std::string& anchor) const {
    if (!obj.contains(key) || !obj[key].is_array() || obj[key].size() != 3) {
      Fail(anchor, where + "/" + key, "expected an array of 3 numbers");
    }
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      if (!obj[key][i].is_number())
        Fail(anchor, where + "/" + key, "expected an array of 3 numbers");
      v[i] = obj[key][i].get<double>();
    }
    if (!v.allFinite()) Fail(anchor, where + "/" + key, "expected finite numbers");
    return v;
  }

 private:
  int LineAt(size_t byte) const {
    const size_t end = std::min(byte, text_.size());
    return 1 + static_cast<int>(std::count(text_.begin(), text_.begin() + end, '\n'));
  }

  std::string path_;
  std::string text_;
  json root_;
};

Intrinsics ReadCamera(const JsonFile& f, const std::string& id, const json& c) {
  const std::string where = "cameras/" + id;
  if (!c.is_object()) f.Fail(id, where, "expected an object");
  if (c.contains("projection_type") && !c["projection_type"].is_string())
    f.Fail(id, where + "/projection_type", "expected a string");
  const std::string type = c.value("projection_type", "");
  const double wd = f.Number(c, "width", where, id), hd = f.Number(c, "height", where, id);
  // Checked before the cast: a double past int's range converts with UB.
  if (!(wd >= 1 && hd >= 1 && wd <= 1 << 20 && hd <= 1 << 20))
    f.Fail(id, where, "expected a width and height of 1 to 1048576 px");
  const int w = static_cast<int>(wd), h = static_cast<int>(hd);
  const double size = std::max(w, h);
  Intrinsics k;
  if (type == "perspective") {
    const double focal = f.Number(c, "focal", where, id) * size;
    k = Intrinsics::FromPixels(focal, focal, 0.5 * (w - 1), 0.5 * (h - 1), w, h);
    k.distortion.k1 = c.contains("k1") ? f.Number(c, "k1", where, id) : 0.0;
    k.distortion.k2 = c.contains("k2") ? f.Number(c, "k2", where, id) : 0.0;
  } else if (type == "brown" || type == "simple_radial" || type == "radial") {
    k = Intrinsics::FromPixels(f.Number(c, "focal_x", where, id) * size,
                               f.Number(c, "focal_y", where, id) * size,
                               0.5 * (w - 1) + f.Number(c, "c_x", where, id) * size,
                               0.5 * (h - 1) + f.Number(c, "c_y", where, id) * size, w, h);
    k.distortion.k1 = f.Number(c, "k1", where, id);
    if (type != "simple_radial") k.distortion.k2 = f.Number(c, "k2", where, id);
    if (type == "brown") {
      k.distortion.k3 = f.Number(c, "k3", where, id);
      k.distortion.p1 = f.Number(c, "p1", where, id);
      k.distortion.p2 = f.Number(c, "p2", where, id);
    }
  } else {
    f.Fail(id, where + "/projection_type",
           "unsupported projection type '" + type +
               "': expected perspective, brown, simple_radial or radial");
  }
  if (!(k.fx > 0 && k.fy > 0)) f.Fail(id, where, "expected a positive focal length");
  return k;
}

// `latitude`, `longitude`, `altitude` of `obj`; errors name the line of the
// key at fault, or `missing_line` for a key that is not there.
GeoReference ReadReference(const JsonFile& f, const json& obj, int missing_line) {
  const std::string where = "reference_lla";
  GeoReference r;
  double* values[] = {&r.latitude, &r.longitude, &r.altitude};
  const char* keys[] = {"latitude", "longitude", "altitude"};
  for (int i = 0; i < 3; ++i) {
    if (!obj.is_object() || !obj.contains(keys[i])) {
      throw InputError(
          f.path(), missing_line,
          where + ": missing number '" + keys[i] + "' (expected latitude, longitude and altitude)");
    }
    *values[i] = f.Number(obj, keys[i], where, keys[i]);
  }
  if (const std::string p = r.Problem(); !p.empty()) {
    const char* key = p.find("longitude =") != std::string::npos ? "longitude" : "latitude";
    f.Fail(key, where + "/" + key, "expected " + p);
  }
  return r;
}

// Moves an OpenSfM block with a reference point into UTM, from whichever of
// the frames of topocentric_to_utm.h its cameras are in: ODM's UTM offset
// when ODM kept the topocentric reconstruction beside it or when the shots'
// GPS positions say so, else OpenSfM's topocentric frame.
void Georeference(const GeoReference& reference, const std::string& reference_from,
                  const fs::path& path, const std::vector<Eigen::Vector3d>& gps, Block* block) {
  char note[640];
  std::string evidence;
  bool utm_offset = false;
  if (fs::exists(path.parent_path() / "reconstruction.topocentric.json")) {
    utm_offset = true;
    evidence = "reconstruction.topocentric.json beside it";
  } else if (gps.size() == block->images.size() && gps.size() >= 2) {
    std::vector<Eigen::Vector3d> centres;
    for (const BlockImage& im : block->images) centres.push_back(im.camera.center());
    const FrameFit fit = FitFramesToGps(TopocentricToUtm(reference), centres, gps);
    utm_offset = fit.utm_offset_rms < fit.topocentric_rms;
    std::snprintf(note, sizeof(note),
                  "camera centres %.3g m RMS from the shots' GPS read as UTM offsets, %.3g m "
                  "read as topocentric",
                  fit.utm_offset_rms, fit.topocentric_rms);
    evidence = note;
  }
  if (utm_offset) {
    MoveUtmOffsetToUtm(reference, block);
    std::snprintf(note, sizeof(note),
                  "UTM from ODM's reconstruction in UTM less the easting and northing of lat "
                  "%.8f, lon %.8f (%s; %s)",
                  reference.latitude, reference.longitude, reference_from.c_str(),
                  evidence.c_str());
    block->frame_note = note;
    return;
  }
  const TopocentricToUtmReport moved = MoveTopocentricToUtm(reference, block);
  std::snprintf(note, sizeof(note),
                "UTM from OpenSfM's topocentric ENU about lat %.8f, lon %.8f, alt %.3f (%s%s%s); "
                "camera rotations turned by the grid convergence %.4f deg, scale %.6f",
                reference.latitude, reference.longitude, reference.altitude, reference_from.c_str(),
                evidence.empty() ? "" : "; ", evidence.c_str(), moved.convergence_deg, moved.scale);
  block->frame_note = note;
  if (moved.max_reprojection_change_px >= 0) {
    std::snprintf(note, sizeof(note),
                  "; sparse points reproject within %.3g px of ENU (%d checked)",
                  moved.max_reprojection_change_px, moved.points_checked);
    block->frame_note += note;
  }
}

fs::path JsonPath(const fs::path& given) {
  if (fs::is_regular_file(given)) return given;
  if (fs::is_regular_file(given / "reconstruction.json")) return given / "reconstruction.json";
  return given / "opensfm" / "reconstruction.json";
}

}  // namespace

namespace {

Block ReadOpenSfmFile(const fs::path& path, const BlockReadOptions& options) {
  const JsonFile f(path);
  const json& root = f.root();
  if (!root.is_array() || root.empty() || !root[0].is_object()) {
    throw InputError(path.string(), 1, "expected an array of reconstructions");
  }
  const json& rec = root[0];
  if (!rec.contains("cameras") || !rec["cameras"].is_object())
    f.Fail("cameras", "[0]", "missing object 'cameras'");
  if (!rec.contains("shots") || !rec["shots"].is_object())
    f.Fail("shots", "[0]", "missing object 'shots'");

  std::map<std::string, Intrinsics> cameras;
  for (const auto& [id, c] : rec["cameras"].items()) cameras[id] = ReadCamera(f, id, c);

  fs::path image_dir = options.image_dir;
  if (image_dir.empty()) {
    image_dir = path.parent_path() / "images";
    if (!fs::is_directory(image_dir)) image_dir = path.parent_path().parent_path() / "images";
  }

  Block block;
  // Read before the shots: a bad reference point fails before image lookups.
  std::optional<GeoReference> reference;
  std::string reference_from;
  const fs::path lla_file = path.parent_path() / "reference_lla.json";
  if (rec.contains("reference_lla")) {
    reference = ReadReference(f, rec["reference_lla"], f.LineOf("reference_lla"));
    reference_from = "reference_lla in " + path.filename().string();
  } else if (fs::exists(lla_file)) {
    const JsonFile lla(lla_file);
    if (!lla.root().is_object()) {
      throw InputError(lla_file.string(), 1,
                       "expected an object {\"latitude\": .., \"longitude\": .., "
                       "\"altitude\": ..}");
    }
    reference = ReadReference(lla, lla.root(), 1);
    reference_from = lla_file.filename().string();
  }

  std::vector<Eigen::Vector3d> gps;  // OpenSfM's topocentric GPS positions of the shots
  for (const auto& [id, shot] : rec["shots"].items()) {
    const std::string where = "shots/" + id;
    if (!shot.is_object() || !shot.contains("camera") || !shot["camera"].is_string()) {
      f.Fail(id, where, "expected an object with a 'camera' name");
    }
    const auto cam = cameras.find(shot["camera"].get<std::string>());
    if (cam == cameras.end())
      f.Fail(id, where + "/camera", "unknown camera '" + shot["camera"].get<std::string>() + "'");
    const Eigen::Vector3d aa = f.Vector3(shot, "rotation", where, id);
    const Eigen::Vector3d t = f.Vector3(shot, "translation", where, id);
    const double angle = aa.norm();
    const Eigen::Matrix3d r = angle < 1e-15
                                  ? Eigen::Matrix3d::Identity()
                                  : Eigen::AngleAxisd(angle, aa / angle).toRotationMatrix();
    BlockImage im;
    im.name = id;
    im.camera_name = cam->first;
    im.camera = Camera(cam->second, r, -r.transpose() * t);
    im.path = FindImageFile(image_dir, id);
    if (im.path.empty())
      f.Fail(id, where, "no image for shot '" + id + "' in " + image_dir.string());
    block.images.push_back(std::move(im));
    // Optional metadata, used only to tell the frame: a shot without a
    // usable one leaves the choice to the file layout.
    const json* g = shot.contains("gps_position") ? &shot["gps_position"] : nullptr;
    if (g && g->is_array() && g->size() == 3 && (*g)[0].is_number() && (*g)[1].is_number() &&
        (*g)[2].is_number()) {
      gps.emplace_back((*g)[0].get<double>(), (*g)[1].get<double>(), (*g)[2].get<double>());
    }
  }
  if (rec.contains("points") && rec["points"].is_object()) {
    for (const auto& [id, p] : rec["points"].items()) {
      block.sparse_points.push_back(f.Vector3(p, "coordinates", "points/" + id, id));
    }
  }
  if (reference) {
    Georeference(*reference, reference_from, path, gps, &block);
  } else {
    block.frame_note = "OpenSfM local frame (no reference_lla)";
  }
  if (root.size() > 1) block.frame_note += "; reconstruction 1 of " + std::to_string(root.size());
  return block;
}

}  // namespace

Block ReadOpenSfmBlock(const fs::path& given, const BlockReadOptions& options) {
  const fs::path path = JsonPath(given);
  try {
    return ReadOpenSfmFile(path, options);
  } catch (const json::exception& e) {
    // A value of a type the checks above did not foresee: still one line
    // naming the file, without the library's prefix.
    throw InputError(path.string(), 0, "unexpected JSON content: " + JsonDetail(e));
  }
}

}  // namespace sapmvs

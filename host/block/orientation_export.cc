#include "block/orientation_export.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "sapmvs/block/rotation.h"
#include "sapmvs/util/error.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

const char* const kPix4dSuffix = "_calibrated_external_camera_parameters.txt";
const char* const kPix4dWgs84Suffix = "_calibrated_external_camera_parameters_wgs84.txt";
const std::vector<std::string> kPoseColumns = {"X", "Y", "Z", "Omega", "Phi", "Kappa"};
const std::vector<std::string> kMatrixColumns = {"r11", "r12", "r13", "r21", "r22",
                                                 "r23", "r31", "r32", "r33"};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// Windows editors and some exporters start the file with a UTF-8 BOM.
void DropBom(std::string* line) {
  if (line->rfind("\xEF\xBB\xBF", 0) == 0) line->erase(0, 3);
}

// Metashape separates by tabs, or by commas when asked to; a PhotoID may hold
// spaces, so spaces split only a file that has neither.
std::vector<std::string> SplitMetashape(const std::string& line) {
  const char sep = line.find('\t') != std::string::npos  ? '\t'
                   : line.find(',') != std::string::npos ? ','
                                                         : '\0';
  if (sep == '\0') return SplitWhitespace(line);
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t end = line.find(sep, start);
    out.push_back(Trim(line.substr(start, end - start)));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  while (!out.empty() && out.back().empty()) out.pop_back();  // a trailing separator
  return out;
}

std::string Join(const std::vector<std::string>& names, const char* sep) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : sep) + n;
  return out;
}

// Names seen so far, with the line of each: an image listed twice would be
// matched with itself.
class SeenNames {
 public:
  void Add(const std::string& name, const TextLines& lines) {
    const auto [it, fresh] = first_.emplace(name, lines.line());
    if (!fresh) {
      throw lines.Fail("image '" + name + "' listed twice (first on line " +
                       std::to_string(it->second) + ")");
    }
  }

 private:
  std::map<std::string, int> first_;
};

ExportedPose PoseFromAngles(const std::string& name, const TextLines& lines,
                            const std::vector<std::string>& fields) {
  double v[6];
  for (size_t i = 0; i < 6; ++i) v[i] = lines.Double(fields[i + 1], kPoseColumns[i]);
  ExportedPose pose;
  pose.name = name;
  pose.line = lines.line();
  pose.center = Eigen::Vector3d(v[0], v[1], v[2]);
  pose.camera_to_world =
      CameraToWorldFromAngles(v[3], v[4], v[5], AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  return pose;
}

}  // namespace

OrientationFormat ParseOrientationFormat(std::string_view text) {
  if (text == "auto") return OrientationFormat::kAuto;
  if (text == "plain") return OrientationFormat::kPlain;
  if (text == "metashape") return OrientationFormat::kMetashape;
  if (text == "pix4d") return OrientationFormat::kPix4d;
  throw Error("unknown orientation format '" + std::string(text) +
              "': expected auto, plain, metashape or pix4d");
}

std::string ToString(OrientationFormat format) {
  switch (format) {
    case OrientationFormat::kAuto:
      return "auto";
    case OrientationFormat::kPlain:
      return "plain";
    case OrientationFormat::kMetashape:
      return "metashape";
    case OrientationFormat::kPix4d:
      return "pix4d";
  }
  return "?";
}

OrientationFormat DetectOrientationFormat(const fs::path& path) {
  const std::string file = path.filename().string();
  if (EndsWith(file, kPix4dSuffix) || EndsWith(file, kPix4dWgs84Suffix)) {
    return OrientationFormat::kPix4d;
  }
  TextLines lines(path);
  std::string line;
  while (lines.NextRaw(&line, false)) {
    DropBom(&line);
    const std::string t = Trim(line);
    if (t.empty()) continue;
    if (t.rfind("# Cameras (", 0) == 0 || t.rfind("# PhotoID", 0) == 0) {
      return OrientationFormat::kMetashape;
    }
    if (t[0] == '#') continue;  // a comment of sapmvs's own format
    const std::vector<std::string> f = SplitWhitespace(t);
    if (Lower(f[0]) == "imagename") return OrientationFormat::kPix4d;
    return OrientationFormat::kPlain;
  }
  return OrientationFormat::kPlain;
}

std::vector<ExportedPose> ReadMetashapeOpk(const fs::path& path) {
  TextLines lines(path);
  std::vector<ExportedPose> poses;
  SeenNames seen;
  // Without the header (a user may strip comments) both of Metashape's
  // layouts are taken; with it, the one it names.
  size_t columns = 0;
  std::string line;
  while (lines.NextRaw(&line, false)) {
    if (lines.line() == 1) DropBom(&line);
    const std::string t = Trim(line);
    if (t.empty()) continue;
    if (t[0] == '#') {
      if (t.rfind("# PhotoID", 0) != 0) continue;  // `# Cameras (N)` and other notes
      std::vector<std::string> names = SplitMetashape(t.substr(2));
      std::vector<std::string> expect = {"PhotoID"};
      expect.insert(expect.end(), kPoseColumns.begin(), kPoseColumns.end());
      std::vector<std::string> with_matrix = expect;
      with_matrix.insert(with_matrix.end(), kMatrixColumns.begin(), kMatrixColumns.end());
      if (names == expect || names == with_matrix) {
        columns = names.size();
        continue;
      }
      throw lines.Fail("unknown Metashape header '" + t + "': expected '# " + Join(expect, ", ") +
                       "' with or without ', r11, ..., r33'");
    }
    const std::vector<std::string> f = SplitMetashape(t);
    const bool fits = columns ? f.size() == columns : (f.size() == 7 || f.size() == 16);
    if (!fits) {
      throw lines.Fail("expected " + (columns ? std::to_string(columns) : std::string("7 or 16")) +
                       " fields (PhotoID, X, Y, Z, Omega, Phi, Kappa" +
                       (columns == 7    ? ""
                        : columns == 16 ? ", r11 .. r33"
                                        : "[, r11 .. r33]") +
                       "), got " + std::to_string(f.size()));
    }
    if (f[0].empty()) throw lines.Fail("expected a PhotoID in the first field, got nothing");
    ExportedPose pose = PoseFromAngles(f[0], lines, f);
    if (f.size() == 16) {
      Eigen::Matrix3d m;
      for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = lines.Double(f[7 + i], kMatrixColumns[i]);
      const Eigen::Matrix3d r_pg = m.transpose();
      const double gap = (r_pg - pose.camera_to_world).cwiseAbs().maxCoeff();
      if (!(gap <= kMaxMatrixMismatch)) {
        char detail[160];
        std::snprintf(detail, sizeof(detail),
                      "r11 .. r33 disagree with Omega Phi Kappa (max difference %.3g, expected "
                      "<= %.0e): expected the transpose of Rx(omega) Ry(phi) Rz(kappa)",
                      gap, kMaxMatrixMismatch);
        throw lines.Fail(detail);
      }
      // The matrix carries more digits than the angles.
      try {
        pose.camera_to_world = CheckedRotation(r_pg, "r11 .. r33");
      } catch (const InputError&) {
        throw;
      } catch (const Error& e) {
        throw lines.Fail(e.what());
      }
    }
    seen.Add(pose.name, lines);
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) throw InputError(path.string(), 0, "no cameras in the Metashape export");
  return poses;
}

std::vector<ExportedPose> ReadPix4dExternal(const fs::path& path) {
  TextLines lines(path);
  std::vector<ExportedPose> poses;
  SeenNames seen;
  const bool wgs84_name = EndsWith(path.filename().string(), kPix4dWgs84Suffix);
  const std::string projected =
      wgs84_name ? path.filename().string().substr(
                       0, path.filename().string().size() - std::string(kPix4dWgs84Suffix).size()) +
                       kPix4dSuffix
                 : std::string("*") + kPix4dSuffix;
  const std::string refusal =
      "Pix4D's WGS84 export (latitude, longitude) is not read: expected the projected export " +
      projected + " beside it, with block.yaml's crs set to the project's output CRS";
  const std::string layout = "imageName X Y Z Omega Phi Kappa";
  std::vector<std::string> f;
  std::string line;
  while (lines.NextRaw(&line)) {
    if (lines.line() == 1) DropBom(&line);
    f = SplitWhitespace(line);
    if (f.empty()) continue;
    const std::string first = Lower(f[0]);
    if (first == "imagename") {
      bool geographic = wgs84_name;
      for (const std::string& name : f) {
        const std::string n = Lower(name);
        geographic = geographic || n == "latitude" || n == "longitude" || n == "lat" || n == "lon";
      }
      if (geographic) throw lines.Fail(refusal);
      std::vector<std::string> names = {"imagename"};
      for (const std::string& c : kPoseColumns) names.push_back(Lower(c));
      std::vector<std::string> got;
      for (const std::string& name : f) got.push_back(Lower(name));
      if (got != names) {
        throw lines.Fail("unknown Pix4D header '" + Trim(line) + "': expected '" + layout + "'");
      }
      continue;
    }
    if (wgs84_name) throw lines.Fail(refusal);
    lines.ExpectCount(f, 7, layout);
    ExportedPose pose = PoseFromAngles(f[0], lines, f);
    seen.Add(pose.name, lines);
    poses.push_back(std::move(pose));
  }
  if (poses.empty()) throw InputError(path.string(), 0, "no cameras in the Pix4D export");
  return poses;
}

}  // namespace sapmvs

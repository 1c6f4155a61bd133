#include "sapmvs/block/block_export.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "sapmvs/block/export_frame.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/number_text.h"
#include "sapmvs/util/progress.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace fs = std::filesystem;

ExportFormat ParseExportFormat(std::string_view text) {
  if (text == "pmvs") return ExportFormat::kPmvs;
  if (text == "colmap") return ExportFormat::kColmap;
  throw Error("unknown export format '" + std::string(text) + "': expected pmvs or colmap");
}

std::string ToString(ExportFormat format) {
  return format == ExportFormat::kPmvs ? "pmvs" : "colmap";
}

int ExportOptions::Level() const {
  if (level) return *level;
  return format == ExportFormat::kPmvs ? 1 : 0;
}

std::string ExportOptions::Problem() const {
  if (out.empty()) return "an output folder (--out)";
  if (Level() < 0 || Level() > kMaxLevel) {
    return "level in 0.." + std::to_string(kMaxLevel) + " (level = " + std::to_string(Level()) +
           ")";
  }
  if (jpeg_quality < 1 || jpeg_quality > 100) {
    return "jpeg_quality in 1..100 (jpeg_quality = " + std::to_string(jpeg_quality) + ")";
  }
  return "";
}

bool ExportOptions::Check() const {
  const std::string p = Problem();
  if (!p.empty()) std::cerr << "ExportOptions: expected " << p << "\n";
  return p.empty();
}

void CheckExportTarget(const fs::path& out) {
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec)) throw Error(out.string() + ": exists and is not a folder");
  if (fs::is_empty(out, ec)) return;
  if (fs::is_regular_file(out / kExportFrameFile) || fs::is_regular_file(out / kExportMarkerFile))
    return;
  throw Error(out.string() + ": folder is not empty and was not written by sapmvs export (no " +
              kExportFrameFile + "); give a new or empty folder");
}

namespace {

// One image as it is written: where, how encoded, and its camera (pinhole,
// at the export's level, world frame).
struct ExportImage {
  fs::path file;  // relative to the output folder
  ImageEncoding encoding = ImageEncoding::kPng;
  Camera camera;
  fs::path camera_file;  // pmvs: txt/NNNNNNNN.txt, relative to the output folder
};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string Name8(size_t i) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%08zu", i);
  return buf;
}

// COLMAP keeps the images' names, so they keep their format where GDAL can
// write it; the rest (grey PGM, JPEG 2000) become PNG, losslessly.
ExportImage ColmapImage(const BlockImage& im) {
  fs::path name = fs::path(im.name).filename();
  if (!HasImageExtension(name)) name += im.path.extension();
  const std::string ext = Lower(name.extension().string());
  static const std::map<std::string, ImageEncoding> kEncodings = {
      {".jpg", ImageEncoding::kJpeg},  {".jpeg", ImageEncoding::kJpeg},
      {".png", ImageEncoding::kPng},   {".tif", ImageEncoding::kTiff},
      {".tiff", ImageEncoding::kTiff}, {".bmp", ImageEncoding::kBmp},
      {".ppm", ImageEncoding::kPpm}};
  const auto it = kEncodings.find(ext);
  ExportImage e;
  e.encoding = it != kEncodings.end() && CanEncode(it->second) ? it->second : ImageEncoding::kPng;
  if (e.encoding == ImageEncoding::kPng && ext != ".png") name.replace_extension(".png");
  e.file = fs::path("images") / name;
  return e;
}

std::vector<ExportImage> PlanImages(const Block& block, const ExportOptions& o) {
  const double scale = std::ldexp(1.0, -o.Level());
  std::vector<ExportImage> plan;
  std::map<fs::path, std::string> taken;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& im = block.images[i];
    ExportImage e;
    if (o.format == ExportFormat::kPmvs) {
      // PMVS2 finds visualize/NNNNNNNN.jpg; it applies its level itself.
      e.file = fs::path("visualize") / (Name8(i) + ".jpg");
      e.camera_file = fs::path("txt") / (Name8(i) + ".txt");
      e.encoding = ImageEncoding::kJpeg;
      e.camera = im.camera.Pinhole();
    } else {
      e = ColmapImage(im);
      e.camera = im.camera.Pinhole().Scaled(scale);
    }
    e.camera.intrinsics().Validate("image '" + im.name + "' at level " + std::to_string(o.Level()));
    const auto [it, fresh] = taken.emplace(e.file, im.name);
    if (!fresh) {
      throw Error("images '" + it->second + "' and '" + im.name + "' would both be written as " +
                  e.file.string());
    }
    plan.push_back(std::move(e));
  }
  return plan;
}

bool IsInside(const fs::path& file, const fs::path& dir) {
  std::error_code ec;
  const fs::path f = fs::weakly_canonical(file, ec);
  const fs::path d = fs::weakly_canonical(dir, ec);
  return std::mismatch(f.begin(), f.end(), d.begin(), d.end()).second == d.end();
}

// P = K [R | t] of the undistorted image, PMVS's pixel convention being ours
// (pixel centres at integers).
std::string PmvsCameraText(const Camera& local) {
  const Eigen::Matrix<double, 3, 4> p = local.ProjectionMatrix();
  std::string s = "CONTOUR\n";
  for (int r = 0; r < 3; ++r) {
    s += FormatNumber(p(r, 0), 17) + " " + FormatNumber(p(r, 1), 17) + " " +
         FormatNumber(p(r, 2), 17) + " " + FormatNumber(p(r, 3), 17) + "\n";
  }
  return s;
}

std::string PmvsOptionText(int level, size_t images) {
  const unsigned cpus = std::max(1u, std::thread::hardware_concurrency());
  std::ostringstream s;
  s << "level " << level << "\ncsize 2\nthreshold 0.7\nwsize 7\nminImageNum 3\nCPU " << cpus
    << "\nuseVisData 0\nsequence -1\nmaxAngle 10\nquad 2.0\ntimages -1 0 " << images
    << "\noimages 0\n";
  return s.str();
}

struct ColmapText {
  std::string cameras, images;
  int num_cameras = 0;
};

// COLMAP's pixel corner is 0, 0 (centres at half-integers), hence + 0.5.
ColmapText ColmapModelText(const std::vector<ExportImage>& plan, const Eigen::Vector3d& origin) {
  std::vector<Intrinsics> cameras;
  std::string lines;
  for (size_t i = 0; i < plan.size(); ++i) {
    const Camera local = plan[i].camera.Translated(origin);
    const Intrinsics& k = local.intrinsics();
    const auto same = [&](const Intrinsics& c) {
      return c.width == k.width && c.height == k.height && c.fx == k.fx && c.fy == k.fy &&
             c.cx == k.cx && c.cy == k.cy;
    };
    auto cam = std::find_if(cameras.begin(), cameras.end(), same);
    if (cam == cameras.end()) cam = cameras.insert(cameras.end(), k);
    Eigen::Quaterniond q(local.rotation());
    if (q.w() < 0) q.coeffs() = -q.coeffs();  // COLMAP's convention: qw >= 0
    const Eigen::Vector3d t = -(local.rotation() * local.center());
    lines += std::to_string(i + 1) + " " + FormatNumber(q.w(), 17) + " " + FormatNumber(q.x(), 17) +
             " " + FormatNumber(q.y(), 17) + " " + FormatNumber(q.z(), 17) + " " +
             FormatNumber(t.x(), 17) + " " + FormatNumber(t.y(), 17) + " " +
             FormatNumber(t.z(), 17) + " " + std::to_string(cam - cameras.begin() + 1) + " " +
             plan[i].file.filename().string() + "\n\n";
  }
  ColmapText text;
  text.num_cameras = static_cast<int>(cameras.size());
  text.cameras =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(cameras.size()) + "\n";
  for (size_t c = 0; c < cameras.size(); ++c) {
    const Intrinsics& k = cameras[c];
    text.cameras += std::to_string(c + 1) + " PINHOLE " + std::to_string(k.width) + " " +
                    std::to_string(k.height) + " " + FormatNumber(k.fx, 17) + " " +
                    FormatNumber(k.fy, 17) + " " + FormatNumber(k.cx + 0.5, 17) + " " +
                    FormatNumber(k.cy + 0.5, 17) + "\n";
  }
  text.images =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(plan.size()) + ", mean observations per image: 0\n" + lines;
  return text;
}

// No colour or track is known for a block's sparse points: grey, error 0,
// empty track.
std::string ColmapPointsText(const std::vector<Eigen::Vector3d>& points,
                             const Eigen::Vector3d& origin) {
  std::string s =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: " +
      std::to_string(points.size()) + ", mean track length: 0\n";
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p = points[i] - origin;
    s += std::to_string(i + 1) + " " + FormatNumber(p.x(), 17) + " " + FormatNumber(p.y(), 17) +
         " " + FormatNumber(p.z(), 17) + " 128 128 128 0\n";
  }
  return s;
}

// Every file this export writes besides the side file and the marker.
std::vector<fs::path> PlannedFiles(const std::vector<ExportImage>& plan, ExportFormat format) {
  std::vector<fs::path> files;
  for (const ExportImage& e : plan) {
    files.push_back(e.file);
    if (!e.camera_file.empty()) files.push_back(e.camera_file);
  }
  if (format == ExportFormat::kPmvs) {
    files.push_back("option");
  } else {
    for (const char* f : {"cameras.txt", "images.txt", "points3D.txt"})
      files.push_back(fs::path("sparse") / "0" / f);
  }
  return files;
}

// Makes `out` ready: the marker lists the files of both exports until this one
// is complete, so an interrupted re-export can still clean up after both; the
// earlier export's side file goes first, so the folder never passes for a
// finished export while it holds a mix.
void PrepareFolder(const fs::path& out, const std::vector<fs::path>& files, ExportFormat format) {
  const std::vector<fs::path> old = ReadExportMarker(out);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw Error(out.string() + ": cannot create the folder (" + ec.message() + ")");
  std::vector<fs::path> both = files;
  for (const fs::path& f : old) {
    if (std::find(files.begin(), files.end(), f) == files.end()) both.push_back(f);
  }
  WriteExportMarker(out, both);
  fs::remove(out / kExportFrameFile, ec);
  for (size_t i = files.size(); i < both.size(); ++i) {
    fs::remove(out / both[i], ec);
    // Folders it leaves empty go too (remove refuses non-empty ones).
    for (fs::path d = both[i].parent_path(); !d.empty() && d != "models"; d = d.parent_path())
      fs::remove(out / d, ec);
  }
  for (const fs::path& f : files) {
    fs::create_directories(out / f.parent_path(), ec);
    if (ec)
      throw Error((out / f.parent_path()).string() + ": cannot create (" + ec.message() + ")");
  }
  if (format == ExportFormat::kPmvs) fs::create_directories(out / "models", ec);
}

}  // namespace

ExportSummary ExportBlock(const Block& block, const ExportOptions& options) {
  if (const std::string p = options.Problem(); !p.empty()) {
    throw Error("export options: expected " + p);
  }
  if (block.images.empty()) throw Error(block.source.string() + ": block has no images");
  CheckExportTarget(options.out);
  for (const BlockImage& im : block.images) {
    if (IsInside(im.path, options.out)) {
      throw Error(options.out.string() + ": holds the block's own image " + im.path.string() +
                  "; export to another folder");
    }
  }
  const std::vector<ExportImage> plan = PlanImages(block, options);
  const std::vector<fs::path> files = PlannedFiles(plan, options.format);
  const fs::path& out = options.out;
  PrepareFolder(out, files, options.format);

  const bool pmvs = options.format == ExportFormat::kPmvs;
  const bool show = options.progress && Progress::TerminalAllowsProgress();
  for (size_t i = 0; i < plan.size(); ++i) {
    const ExportImage& e = plan[i];
    if (show) {
      std::fprintf(stderr, "export %zu/%zu: %s -> %s\n", i + 1, plan.size(),
                   block.images[i].name.c_str(), e.file.string().c_str());
    }
    const LoadedImage loaded = LoadUndistorted(block.images[i]);
    const cv::Mat pixels =
        pmvs ? loaded.pixels
             : ResampleToLevel(loaded.pixels, options.Level(), e.camera.width(), e.camera.height());
    const std::vector<uchar> bytes =
        EncodeImage(pixels, e.encoding, (out / e.file).string(), options.jpeg_quality);
    WriteBytesAtomically(out / e.file, bytes.data(), bytes.size());
    if (pmvs) {
      WriteTextAtomically(out / e.camera_file, PmvsCameraText(e.camera.Translated(block.origin)));
    }
  }

  ExportSummary summary;
  summary.out = out;
  summary.format = options.format;
  summary.level = options.Level();
  summary.images = static_cast<int>(plan.size());
  summary.origin = block.origin;
  if (pmvs) {
    WriteTextAtomically(out / "option", PmvsOptionText(options.Level(), plan.size()));
    summary.cameras = summary.images;
  } else {
    const fs::path model = out / "sparse" / "0";
    const ColmapText text = ColmapModelText(plan, block.origin);
    WriteTextAtomically(model / "cameras.txt", text.cameras);
    WriteTextAtomically(model / "images.txt", text.images);
    WriteTextAtomically(model / "points3D.txt",
                        ColmapPointsText(block.sparse_points, block.origin));
    summary.cameras = text.num_cameras;
    summary.points = static_cast<long>(block.sparse_points.size());
  }

  ExportFrame frame;
  frame.format = ToString(options.format);
  frame.level = options.Level();
  frame.origin = block.origin;
  frame.crs = block.crs;
  std::error_code ec;
  const fs::path source = fs::absolute(block.source, ec);
  frame.source = (ec ? block.source : source.lexically_normal()).string();
  frame.sapmvs_version = SAPMVS_VERSION;
  for (const BlockImage& im : block.images) frame.images.push_back(im.name);
  frame.ground_height = block.ground_height;
  if (!block.dem.empty()) frame.dem = fs::absolute(block.dem, ec).lexically_normal().string();
  WriteExportFrame(out, frame);
  WriteExportMarker(out, files);
  return summary;
}

}  // namespace sapmvs

// Writes the seeds that the shared data sets do not provide, with sapmvs's own
// writers where it has them (PLY, LAS, the export side file), into
// OUT/<target>/: `make_seeds OUT`. Multi-file inputs are joined with
// fuzz::kSeparator, as the targets split them.
#include <Eigen/Geometry>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "device/program_binary_cache.h"
#include "fuzz_util.h"
#include "sapmvs/block/export_frame.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/run/cloud_las.h"

using namespace sapmvs;
namespace fs = std::filesystem;

namespace {

std::string Slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string Join(const std::vector<std::string>& parts) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i) out += fuzz::kSeparator;
    out += parts[i];
  }
  return out;
}

template <typename T>
void Put(std::string* s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  s->append(b, sizeof(T));
}

struct Pose {
  Eigen::Quaterniond q;
  Eigen::Vector3d t;
};

// One camera per model id 0-4, two posed images naming stand-in files.
void ColmapSeeds(const fs::path& out) {
  const std::vector<std::pair<int, std::vector<double>>> cams = {
      {0, {500, 320, 240}},
      {1, {500, 510, 320, 240}},
      {2, {500, 320, 240, -0.1}},
      {3, {500, 320, 240, -0.1, 0.02}},
      {4, {500, 510, 320, 240, -0.1, 0.02, 0.001, -0.002}}};
  const char* names[] = {"SIMPLE_PINHOLE", "PINHOLE", "SIMPLE_RADIAL", "RADIAL", "OPENCV"};
  const Pose poses[] = {
      {Eigen::Quaterniond(1, 0, 0, 0), {0, 0, 5}},
      {Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY())), {-1, 0, 5}}};
  const char* images[] = {"0000.jpg", "0001.jpg"};

  std::ostringstream ct, it, pt;
  std::string cb, ib, pb;
  ct << std::setprecision(17) << "# Camera list\n";
  it << std::setprecision(17) << "# Image list\n";
  Put<uint64_t>(&cb, cams.size());
  for (const auto& [id, params] : cams) {
    ct << id + 1 << " " << names[id] << " 640 480";
    for (double p : params) ct << " " << p;
    ct << "\n";
    Put<uint32_t>(&cb, id + 1);
    Put<int32_t>(&cb, id);
    Put<uint64_t>(&cb, 640);
    Put<uint64_t>(&cb, 480);
    for (double p : params) Put(&cb, p);
  }
  Put<uint64_t>(&ib, 2);
  for (int i = 0; i < 2; ++i) {
    const Pose& p = poses[i];
    it << i + 1 << " " << p.q.w() << " " << p.q.x() << " " << p.q.y() << " " << p.q.z() << " "
       << p.t.x() << " " << p.t.y() << " " << p.t.z() << " " << 2 * i + 1 << " " << images[i]
       << "\n100.5 200.5 1 300.5 400.5 -1\n";
    Put<uint32_t>(&ib, i + 1);
    for (double v : {p.q.w(), p.q.x(), p.q.y(), p.q.z(), p.t.x(), p.t.y(), p.t.z()}) Put(&ib, v);
    Put<uint32_t>(&ib, 2 * i + 1);
    ib.append(images[i]);
    ib.push_back('\0');
    Put<uint64_t>(&ib, 2);
    for (int j = 0; j < 2; ++j) {
      Put(&ib, 100.5 + j);
      Put(&ib, 200.5);
      Put<uint64_t>(&ib, j == 0 ? 1 : ~uint64_t{0});
    }
  }
  pt << "# 3D point list\n1 0.5 1.5 2.5 10 20 30 0.4 1 0 2 0\n";
  Put<uint64_t>(&pb, 1);
  Put<uint64_t>(&pb, 1);
  for (double v : {0.5, 1.5, 2.5}) Put(&pb, v);
  for (uint8_t c : {10, 20, 30}) Put(&pb, c);
  Put(&pb, 0.4);
  Put<uint64_t>(&pb, 2);
  for (uint32_t v : {1u, 0u, 2u, 0u}) Put(&pb, v);

  // The side file of an export, through sapmvs's writer.
  const fs::path tmp = out / "tmp";
  fs::create_directories(tmp);
  ExportFrame frame;
  frame.format = "colmap";
  frame.origin = Eigen::Vector3d(500000, 4000000, 300);
  frame.crs = "EPSG:32632";
  frame.images = {"0000.jpg", "0001.jpg"};
  frame.ground_height = 250;
  WriteExportFrame(tmp, frame);
  const std::string colmap_frame = Slurp(tmp / kExportFrameFile);
  frame.format = "pmvs";
  frame.level = 1;
  WriteExportFrame(tmp, frame);
  const std::string pmvs_frame = Slurp(tmp / kExportFrameFile);
  fs::remove_all(tmp);

  fs::create_directories(out / "colmap_text");
  fs::create_directories(out / "colmap_binary");
  fuzz::WriteFile(out / "colmap_text" / "model", Join({ct.str(), it.str(), pt.str()}));
  fuzz::WriteFile(out / "colmap_text" / "model_no_points", Join({ct.str(), it.str()}));
  fuzz::WriteFile(out / "colmap_text" / "export",
                  Join({ct.str(), it.str(), pt.str(), colmap_frame}));
  fuzz::WriteFile(out / "colmap_binary" / "model", Join({cb, ib, pb}));
  fuzz::WriteFile(out / "colmap_binary" / "model_no_points", Join({cb, ib}));
  fuzz::WriteFile(out / "colmap_binary" / "export", Join({cb, ib, pb, colmap_frame}));

  // PMVS: P = K [R | t] for an 8x6 image (the targets' stand-in PNGs).
  fs::create_directories(out / "block_pmvs");
  std::vector<std::string> pmvs;
  for (int i = 0; i < 3; ++i) {
    Eigen::Matrix3d k;
    k << 10, 0, 4, 0, 10, 3, 0, 0, 1;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    Eigen::Matrix<double, 3, 4> p;
    p << k * r, k * Eigen::Vector3d(-i, 0, 5);
    std::ostringstream s;
    s << std::setprecision(17) << "CONTOUR\n" << p << "\n";
    pmvs.push_back(s.str());
  }
  fuzz::WriteFile(out / "block_pmvs" / "one", pmvs[0]);
  fuzz::WriteFile(out / "block_pmvs" / "three", Join(pmvs));
  fuzz::WriteFile(out / "block_pmvs" / "export", Join({pmvs[0], pmvs[1], pmvs[2], pmvs_frame}));
}

void CloudSeeds(const fs::path& out) {
  fs::create_directories(out / "ply");
  fs::create_directories(out / "las");
  PointCloud cloud;
  std::vector<PointRecord> records;
  for (int i = 0; i < 4; ++i) {
    CloudPoint p;
    p.position = Eigen::Vector3d(500000.25 + i, 4000000.5 - i, 300 + 0.1 * i);
    p.normal = Eigen::Vector3f(0, 0.6f, 0.8f);
    p.color = {{static_cast<uint8_t>(10 * i), 20, 30}};
    p.score = 0.5f + 0.1f * i;
    p.num_views = 2 + i * 100;  // over 255 once: views stored as int
    cloud.points.push_back(p);
    PointRecord r;
    r.x = p.position.x();
    r.y = p.position.y();
    r.z = p.position.z();
    r.r = ColorTo16(p.color[0]);
    r.classification = 2;
    records.push_back(r);
  }
  cloud.has_normals = cloud.has_colors = cloud.has_scores = cloud.has_views = true;
  cloud.crs = "EPSG:32632";
  WritePly(out / "ply" / "full.ply", cloud);
  cloud.has_normals = cloud.has_colors = cloud.has_scores = cloud.has_views = false;
  cloud.crs.clear();
  cloud.points.resize(2);
  WritePly(out / "ply" / "xyz.ply", cloud);
  fuzz::WriteFile(out / "ply" / "ascii.ply",
                  "ply\nformat ascii 1.0\ncomment crs EPSG:4326\nelement face 1\n"
                  "property list uchar int vertex_indices\nelement vertex 2\nproperty float x\n"
                  "property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
                  "property uchar blue\nproperty float score\nproperty int views\nend_header\n"
                  "3 0 1 1\n1 2 3 255 0 0 0.5 3\n4 5 6 0 255 0 0.25 2\n");
  fuzz::WriteFile(out / "ply" / "big_endian.ply",
                  std::string("ply\nformat binary_big_endian 1.0\nelement vertex 1\n"
                              "property double x\nproperty double y\nproperty double z\n"
                              "property ushort red\nend_header\n") +
                      std::string(26, '\x01'));
  LasWriteOptions o;
  o.creation_day = 1;
  o.creation_year = 2024;
  WriteLas(out / "las" / "plain.las", records, o);
  o.crs = "EPSG:32632";
  WriteLas(out / "las" / "crs.las", records, o);
  // Extra Bytes, as cloud.las has them, in both versions.
  cloud.has_normals = cloud.has_scores = cloud.has_views = true;
  WriteLas(out / "las" / "extra_bytes_12.las", ToLasRecords(cloud), o, ToLasExtras(cloud));
  o.version = LasVersion::k14;
  WriteLas(out / "las" / "extra_bytes_14.las", ToLasRecords(cloud), o, ToLasExtras(cloud));
}

// Two whole entries of the program cache target's key, as Store writes them.
void ProgramCacheSeeds(const fs::path& out) {
  const fs::path tmp = out / "program_cache_tmp";
  const ProgramBinaryCache cache(tmp);
  fs::create_directories(out / "program_cache");
  const std::string key(fuzz::kProgramCacheKey);
  const std::string binaries[] = {std::string("\x7f"
                                              "ELF binary\0\1\2",
                                              15),
                                  std::string(300, 'b')};
  int n = 0;
  for (const std::string& b : binaries) {
    if (!cache.Store(key, std::vector<unsigned char>(b.begin(), b.end()))) {
      throw std::runtime_error("cannot store a program cache seed in " + tmp.string());
    }
    fs::copy_file(cache.EntryPath(key), out / "program_cache" / ("entry" + std::to_string(n++)),
                  fs::copy_options::overwrite_existing);
  }
  fs::remove_all(tmp);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_seeds OUT\n";
    return 2;
  }
  try {
    ColmapSeeds(argv[1]);
    CloudSeeds(argv[1]);
    ProgramCacheSeeds(argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "make_seeds: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// COLMAP's binary model (its default output), little-endian throughout:
//   cameras.bin   u64 count; per camera: u32 CAMERA_ID, i32 MODEL_ID,
//                 u64 WIDTH, u64 HEIGHT, f64 PARAMS[model's count]
//   images.bin    u64 count; per image: u32 IMAGE_ID, f64 QW QX QY QZ TX TY TZ,
//                 u32 CAMERA_ID, NAME (NUL-terminated), u64 num_points2D,
//                 then (f64 X, f64 Y, u64 POINT3D_ID) per 2D point
//   points3D.bin  u64 count; per point: u64 POINT3D_ID, f64 X Y Z, u8 R G B,
//                 f64 ERROR, u64 track length, then (u32 IMAGE_ID,
//                 u32 POINT2D_IDX) per track element
// The camera and pose conventions are those of the text model
// (block_colmap_reader.cc). Every count is checked against the bytes left in
// the file before it is used, so a corrupt count fails in one line instead of
// asking for gigabytes.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <set>

#include "block/colmap_camera.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

// COLMAP's model names by id, for messages about the models sapmvs does not
// read (ids past ColmapModels()).
constexpr const char* kAllModelNames[] = {"SIMPLE_PINHOLE",
                                          "PINHOLE",
                                          "SIMPLE_RADIAL",
                                          "RADIAL",
                                          "OPENCV",
                                          "OPENCV_FISHEYE",
                                          "FULL_OPENCV",
                                          "FOV",
                                          "SIMPLE_RADIAL_FISHEYE",
                                          "RADIAL_FISHEYE",
                                          "THIN_PRISM_FISHEYE",
                                          "RAD_TAN_THIN_PRISM_FISHEYE"};

class BinaryFile {
 public:
  explicit BinaryFile(const fs::path& path) : path_(path.string()) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw Error(path_ + ": not found (expected a regular file)");
    size_ = fs::file_size(path, ec);
    if (ec) throw Error(path_ + ": cannot read (" + ec.message() + ")");
    in_.open(path, std::ios::binary);
    if (!in_) throw Error(path_ + ": cannot open for reading");
  }

  uint64_t left() const { return size_ - pos_; }

  InputError Fail(const std::string& message) const {
    return InputError(path_, 0, "at byte " + std::to_string(pos_) + ": " + message);
  }

  template <typename T>
  T Read(const char* what) {
    T value;
    Bytes(&value, sizeof(T), what);
    return value;  // Little-endian on every platform sapmvs builds for.
  }

  double Finite(const char* what) {
    const double v = Read<double>(what);
    if (!std::isfinite(v)) throw Fail(std::string("expected a finite ") + what);
    return v;
  }

  // A count of records of at least `record_bytes` each that must fit in
  // what is left of the file.
  uint64_t Count(const char* what, uint64_t record_bytes) {
    const uint64_t n = Read<uint64_t>(what);
    if (n > left() / record_bytes) {
      throw Fail(std::string(what) + " is " + std::to_string(n) + ", but the " +
                 std::to_string(left()) + " bytes left hold at most " +
                 std::to_string(left() / record_bytes) + " (" + std::to_string(record_bytes) +
                 " bytes each): the file is truncated or not a COLMAP model");
    }
    return n;
  }

  void Skip(uint64_t n, const char* what) {
    if (n > left()) {
      throw Fail(std::string("truncated: expected ") + what + " (" + std::to_string(n) +
                 " bytes), the file has " + std::to_string(size_) + " bytes");
    }
    in_.seekg(static_cast<std::streamoff>(n), std::ios::cur);
    pos_ += n;
  }

  std::string Name() {
    std::string name;
    for (;;) {
      const char c = Read<char>("an image name ending in a NUL byte");
      if (c == '\0') break;
      name.push_back(c);
    }
    if (name.empty()) throw Fail("empty image name");
    return name;
  }

  void ExpectEnd() const {
    if (left() != 0) {
      throw Fail(std::to_string(left()) +
                 " bytes after the last record: expected the end of the file");
    }
  }

 private:
  void Bytes(void* out, uint64_t n, const char* what) {
    if (n > left() || !in_.read(static_cast<char*>(out), static_cast<std::streamsize>(n))) {
      throw Fail(std::string("truncated: expected ") + what + " (" + std::to_string(n) +
                 " bytes), the file has " + std::to_string(size_) + " bytes");
    }
    pos_ += n;
  }

  std::ifstream in_;
  std::string path_;
  uint64_t size_ = 0;
  uint64_t pos_ = 0;
};

std::map<uint32_t, Intrinsics> ReadCameras(const fs::path& path) {
  BinaryFile f(path);
  std::map<uint32_t, Intrinsics> cameras;
  // A camera record is 24 bytes plus at least 3 parameters.
  const uint64_t n = f.Count("the number of cameras", 24 + 3 * 8);
  for (uint64_t i = 0; i < n; ++i) {
    const uint32_t id = f.Read<uint32_t>("CAMERA_ID");
    const int32_t model_id = f.Read<int32_t>("MODEL_ID");
    const auto& models = ColmapModels();
    if (model_id < 0 || static_cast<size_t>(model_id) >= models.size()) {
      const int known = static_cast<int>(std::size(kAllModelNames));
      const std::string name = model_id >= 0 && model_id < known
                                   ? std::string(" (") + kAllModelNames[model_id] + ")"
                                   : " (not a COLMAP model)";
      throw f.Fail("camera " + std::to_string(id) + ": unsupported camera model id " +
                   std::to_string(model_id) + name +
                   ": expected 0-4 (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV)");
    }
    const ColmapModel& model = models[static_cast<size_t>(model_id)];
    const uint64_t w = f.Read<uint64_t>("WIDTH"), h = f.Read<uint64_t>("HEIGHT");
    constexpr uint64_t kMaxSide = 1u << 20;  // what Intrinsics and images can hold
    if (w == 0 || h == 0 || w > kMaxSide || h > kMaxSide) {
      throw f.Fail("camera " + std::to_string(id) + ": size " + std::to_string(w) + "x" +
                   std::to_string(h) + " px: expected 1 to " + std::to_string(kMaxSide) +
                   " px on each side");
    }
    std::vector<double> p;
    for (int j = 0; j < model.num_params; ++j) p.push_back(f.Finite("camera parameter"));
    if (cameras.count(id)) throw f.Fail("camera " + std::to_string(id) + " defined twice");
    const Intrinsics k = ColmapIntrinsics(model, static_cast<int>(w), static_cast<int>(h), p);
    if (!(k.fx > 0 && k.fy > 0)) {
      throw f.Fail("camera " + std::to_string(id) + ": expected a positive focal length");
    }
    cameras[id] = k;
  }
  f.ExpectEnd();
  if (cameras.empty()) throw InputError(path.string(), 0, "no cameras");
  return cameras;
}

void ReadImages(const fs::path& path, const std::map<uint32_t, Intrinsics>& cameras,
                const fs::path& image_dir, Block* block) {
  BinaryFile f(path);
  // An image record is 68 bytes, a 2-byte name and its 2D point count at least.
  const uint64_t n = f.Count("the number of images", 4 + 7 * 8 + 4 + 2 + 8);
  std::set<std::string> names;
  for (uint64_t i = 0; i < n; ++i) {
    const uint32_t image_id = f.Read<uint32_t>("IMAGE_ID");
    double v[7];
    for (int j = 0; j < 7; ++j) v[j] = f.Finite(j < 4 ? "quaternion" : "translation");
    const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    const std::string image = "image " + std::to_string(image_id);
    if (std::abs(q.norm() - 1) > 1e-3) {
      throw f.Fail(image + ": quaternion QW QX QY QZ has norm " + std::to_string(q.norm()) +
                   ", expected 1");
    }
    const uint32_t cam_id = f.Read<uint32_t>("CAMERA_ID");
    const auto cam = cameras.find(cam_id);
    if (cam == cameras.end()) throw f.Fail(image + ": unknown CAMERA_ID " + std::to_string(cam_id));
    BlockImage im;
    im.name = f.Name();
    if (!names.insert(im.name).second) throw f.Fail("image '" + im.name + "' listed twice");
    const uint64_t num_points = f.Count("the number of 2D points", 24);
    f.Skip(num_points * 24, "the 2D points");
    im.camera_name = "camera " + std::to_string(cam_id);
    const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
    const Eigen::Vector3d tr(v[4], v[5], v[6]);
    im.camera = Camera(cam->second, r, -r.transpose() * tr);
    im.path = FindImageFile(image_dir, im.name);
    if (im.path.empty()) throw f.Fail("no image '" + im.name + "' in " + image_dir.string());
    block->images.push_back(std::move(im));
  }
  f.ExpectEnd();
}

void ReadPoints(const fs::path& path, Block* block) {
  BinaryFile f(path);
  const uint64_t n = f.Count("the number of 3D points", 8 + 3 * 8 + 3 + 8 + 8);
  for (uint64_t i = 0; i < n; ++i) {
    f.Read<uint64_t>("POINT3D_ID");
    Eigen::Vector3d x;
    for (int j = 0; j < 3; ++j) x[j] = f.Finite("point coordinate");
    f.Skip(3 + 8, "colour and reprojection error");
    const uint64_t track = f.Count("the track length", 8);
    f.Skip(track * 8, "the track");
    block->sparse_points.push_back(x);
  }
  f.ExpectEnd();
}

}  // namespace

Block ReadColmapBinaryModel(const fs::path& dir, const fs::path& image_dir) {
  const std::map<uint32_t, Intrinsics> cameras = ReadCameras(dir / "cameras.bin");
  Block block;
  block.frame_note = "COLMAP model frame";
  ReadImages(dir / "images.bin", cameras, image_dir, &block);
  if (fs::is_regular_file(dir / "points3D.bin")) ReadPoints(dir / "points3D.bin", &block);
  return block;
}

}  // namespace sapmvs

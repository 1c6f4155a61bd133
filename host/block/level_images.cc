#include "sapmvs/block/level_images.h"

#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>

#include "sapmvs/block/image_io.h"

namespace sapmvs {
namespace {

constexpr char kMagic[8] = {'S', 'A', 'P', 'M', 'V', 'S', 'L', 'I'};
constexpr uint32_t kVersion = 1;

// What a kept copy must match: the file it came from, as it is now, and
// the level and size it was made at. The path is kept whole, so that two
// images whose names hash alike never take each other's pixels.
struct Header {
  int32_t level = 0, width = 0, height = 0;
  uint64_t file_size = 0;
  int64_t file_time = 0;
  std::string path;
};

std::optional<Header> Expected(const BlockImage& image, int level, int width, int height) {
  const std::optional<FileStamp> stamp = FileStamp::Of(image.path);
  if (!stamp) return std::nullopt;
  Header h;
  h.level = level;
  h.width = width;
  h.height = height;
  h.file_size = stamp->size;
  h.file_time = static_cast<int64_t>(stamp->time.time_since_epoch().count());
  h.path = image.path.string();
  return h;
}

bool SameHeader(const Header& a, const Header& b) {
  return a.level == b.level && a.width == b.width && a.height == b.height &&
         a.file_size == b.file_size && a.file_time == b.file_time && a.path == b.path;
}

template <class T>
void Put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
bool Get(std::istream& in, T* v) {
  return static_cast<bool>(in.read(reinterpret_cast<char*>(v), sizeof *v));
}

std::filesystem::path CopyPath(const std::filesystem::path& dir, const BlockImage& image,
                               int level) {
  std::ostringstream name;
  name << std::hex << std::hash<std::string>{}(image.path.string()) << std::dec << "_L" << level
       << ".bgr";
  return dir / name.str();
}

// The kept pixels, or an empty Mat where there is no usable copy.
cv::Mat ReadCopy(const std::filesystem::path& path, const Header& expected) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  char magic[sizeof kMagic];
  uint32_t version = 0, path_size = 0;
  Header h;
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof kMagic) != 0 ||
      !Get(in, &version) || version != kVersion || !Get(in, &h.level) || !Get(in, &h.width) ||
      !Get(in, &h.height) || !Get(in, &h.file_size) || !Get(in, &h.file_time) ||
      !Get(in, &path_size) || path_size != expected.path.size()) {
    return {};
  }
  h.path.resize(path_size);
  if (!in.read(h.path.data(), path_size) || !SameHeader(h, expected)) return {};
  cv::Mat pixels(h.height, h.width, CV_8UC3);
  const std::streamsize bytes = static_cast<std::streamsize>(pixels.total() * pixels.elemSize());
  if (!in.read(reinterpret_cast<char*>(pixels.data), bytes)) return {};
  return pixels;
}

// Written under a name of this process and thread, then renamed: a reader
// sees a whole copy or none, and two ranks writing the same image leave
// one of two equal copies. No fsync: a copy lost in a crash is decoded again.
// Not written where it would leave less than `min_free` bytes free (< 0:
// 1 GiB and a tenth of the disk).
void WriteCopy(const std::filesystem::path& path, const Header& h, const cv::Mat& pixels,
               double min_free) {
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  if (ec) return;
  const std::filesystem::space_info space = std::filesystem::space(path.parent_path(), ec);
  if (ec) return;
  if (min_free < 0) min_free = 1073741824.0 + 0.1 * static_cast<double>(space.capacity);
  const double bytes = static_cast<double>(pixels.total() * pixels.elemSize()) + 4096;
  if (static_cast<double>(space.available) - bytes < min_free) return;
  std::ostringstream tmp_name;
  tmp_name << path.filename().string() << ".tmp." << ::getpid() << "."
           << std::hash<std::thread::id>{}(std::this_thread::get_id());
  const std::filesystem::path tmp = path.parent_path() / tmp_name.str();
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(kMagic, sizeof kMagic);
    Put(out, kVersion);
    Put(out, h.level);
    Put(out, h.width);
    Put(out, h.height);
    Put(out, h.file_size);
    Put(out, h.file_time);
    Put(out, static_cast<uint32_t>(h.path.size()));
    out.write(h.path.data(), static_cast<std::streamsize>(h.path.size()));
    const cv::Mat whole = pixels.isContinuous() ? pixels : pixels.clone();
    out.write(reinterpret_cast<const char*>(whole.data),
              static_cast<std::streamsize>(whole.total() * whole.elemSize()));
    out.flush();
    if (!out) {
      out.close();
      std::filesystem::remove(tmp, ec);
      return;
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) std::filesystem::remove(tmp, ec);
}

}  // namespace

LevelImageStore::LevelImageStore(std::filesystem::path dir, double min_free_bytes)
    : dir_(std::move(dir)), min_free_bytes_(min_free_bytes) {}

cv::Mat LevelImageStore::Load(const BlockImage& image, int level, int width, int height,
                              bool keep) const {
  const std::optional<Header> expected =
      dir_.empty() ? std::nullopt : Expected(image, level, width, height);
  if (!expected) return ResampleToLevel(LoadUndistorted(image).pixels, level, width, height);
  const std::filesystem::path path = CopyPath(dir_, image, level);
  if (cv::Mat kept = ReadCopy(path, *expected); !kept.empty()) return kept;
  cv::Mat pixels = ResampleToLevel(LoadUndistorted(image).pixels, level, width, height);
  if (keep) WriteCopy(path, *expected, pixels, min_free_bytes_);
  return pixels;
}

const LevelImageStore& StoreOrNone(const LevelImageStore* store) {
  static const LevelImageStore none;
  return store ? *store : none;
}

void LevelImageStore::Clear() const {
  if (dir_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

}  // namespace sapmvs

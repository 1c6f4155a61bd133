#include "sapmvs/block/image_io.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "sapmvs/util/error.h"
#include "util/image_codec.h"
#include "util/input_file.h"

namespace sapmvs {
namespace {

std::string LowerExtension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// A regular, non-empty file; otherwise throws naming the image.
void RequireImageFile(const std::filesystem::path& path, const std::string& image) {
  const std::string problem = NotRegularFile(path);
  const std::string suffix = image.empty() ? "" : " (image '" + image + "')";
  if (problem == "missing") throw Error(path.string() + ": image file not found" + suffix);
  if (!problem.empty()) {
    throw Error(path.string() + ": cannot open image (" + problem + ", expected a regular file)" +
                suffix);
  }
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 && !ec) {
    throw Error(path.string() + ": empty file (0 bytes), expected an image" + suffix);
  }
}

// libjpeg decodes a truncated JPEG with only a warning on stderr and grey
// rows for the missing part, so a cut-off file would be matched as if it were
// whole. A complete JPEG ends with the EOI marker FF D9; entropy-coded data
// cannot hold FF D9 (an FF there is followed by 00 or a restart marker), so an
// EOI near the end means the file is whole. The tail allows for padding or
// trailer data some cameras write after EOI.
void CheckJpegComplete(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char soi[2] = {0, 0};
  if (!in.read(reinterpret_cast<char*>(soi), 2) || soi[0] != 0xFF || soi[1] != 0xD8) return;
  constexpr std::streamoff kTail = 4096;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff start = std::max<std::streamoff>(2, size - kTail);
  std::vector<char> tail(static_cast<size_t>(size - start));
  in.seekg(start);
  if (!in.read(tail.data(), static_cast<std::streamsize>(tail.size()))) return;
  for (size_t i = 0; i + 1 < tail.size(); ++i) {
    if (static_cast<unsigned char>(tail[i]) == 0xFF &&
        static_cast<unsigned char>(tail[i + 1]) == 0xD9) {
      return;
    }
  }
  throw Error(path.string() + ": truncated JPEG (" + std::to_string(size) +
              " bytes, no end-of-image marker), expected a complete image");
}

}  // namespace

bool HasImageExtension(const std::filesystem::path& path) {
  static const char* kExtensions[] = {".tif", ".tiff", ".jpg", ".jpeg", ".png",
                                      ".ppm", ".pgm",  ".bmp", ".jp2"};
  const std::string ext = LowerExtension(path);
  return std::any_of(std::begin(kExtensions), std::end(kExtensions),
                     [&](const char* e) { return ext == e; });
}

ImageSize ReadImageSize(const std::filesystem::path& path) {
  RequireImageFile(path, "");
  CheckJpegComplete(path);
  const cv::Size size = ReadImageFileSize(path);
  return {size.width, size.height};
}

std::filesystem::path FindImageFile(const std::filesystem::path& folder, const std::string& name) {
  namespace fs = std::filesystem;
  // Not only regular files: a FIFO or a link to nothing is found here and
  // refused by name where it is opened, instead of reported as missing.
  // A name from a file can be anything (longer than NAME_MAX, say): an
  // error looking it up means "not found", not an exception.
  std::error_code ec;
  if (fs::exists(fs::symlink_status(folder / name, ec)) && !fs::is_directory(folder / name, ec)) {
    return folder / name;
  }
  if (!fs::is_directory(folder, ec)) return {};
  const std::string stem = fs::path(name).stem().string();
  std::vector<fs::path> hits;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_directory() || !HasImageExtension(entry.path())) continue;
    const std::string s = entry.path().stem().string();
    if (s == name || s == stem) hits.push_back(entry.path());
  }
  if (hits.empty()) return {};
  // Two files that both fit (a.jpg and a.png) may hold different pictures;
  // picking one silently could match the wrong one.
  if (hits.size() > 1) {
    std::sort(hits.begin(), hits.end());
    throw Error(folder.string() + ": image '" + name + "' is ambiguous: " +
                hits[0].filename().string() + " and " + hits[1].filename().string() +
                " both fit (expected one file; remove one or give the name with its extension)");
  }
  return hits.front();
}

cv::Mat LoadImage(const BlockImage& image) {
  RequireImageFile(image.path, image.name);
  CheckJpegComplete(image.path);
  cv::Mat pixels = DecodeImageFile(image.path);
  if (pixels.cols != image.camera.width() || pixels.rows != image.camera.height()) {
    throw Error(image.path.string() + ": image is " + std::to_string(pixels.cols) + "x" +
                std::to_string(pixels.rows) + " px, its camera expects " +
                std::to_string(image.camera.width()) + "x" + std::to_string(image.camera.height()));
  }
  return pixels;
}

cv::Mat Undistort(const cv::Mat& image, const Intrinsics& intrinsics) {
  if (intrinsics.distortion.IsZero()) return image;
  cv::Mat k(3, 3, CV_64F);
  const Eigen::Matrix3d kk = intrinsics.K();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) k.at<double>(r, c) = kk(r, c);
  const Distortion& d = intrinsics.distortion;
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << d.k1, d.k2, d.p1, d.p2, d.k3);
  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(k, dist, cv::Mat(), k, image.size(), CV_32FC1, map_x, map_y);
  cv::Mat out;
  cv::remap(image, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return out;
}

std::optional<FileStamp> FileStamp::Of(const std::filesystem::path& path) {
  std::error_code ec;
  FileStamp stamp;
  stamp.size = std::filesystem::file_size(path, ec);
  if (ec) return std::nullopt;
  stamp.time = std::filesystem::last_write_time(path, ec);
  if (ec) return std::nullopt;
  return stamp;
}

LoadedImage LoadUndistorted(const BlockImage& image) {
  LoadedImage out;
  out.pixels = Undistort(LoadImage(image), image.camera.intrinsics());
  out.camera = image.camera.Pinhole();
  return out;
}

cv::Mat ResampleToLevel(const cv::Mat& image, int level, int width, int height) {
  cv::Mat out = image;
  for (int l = 0; l < level; ++l) {
    cv::Mat half;
    cv::resize(out, half, cv::Size((out.cols + 1) / 2, (out.rows + 1) / 2), 0, 0, cv::INTER_AREA);
    out = half;
  }
  if (out.cols != width || out.rows != height) {
    cv::resize(out, out, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  }
  return out;
}

Eigen::Vector3d BilinearBgr(const cv::Mat& bgr, double x, double y) {
  x = std::clamp(x, 0.0, bgr.cols - 1.0);
  y = std::clamp(y, 0.0, bgr.rows - 1.0);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, bgr.cols - 1), y1 = std::min(y0 + 1, bgr.rows - 1);
  const double fx = x - x0, fy = y - y0;
  const cv::Vec3b& a = bgr.at<cv::Vec3b>(y0, x0);
  const cv::Vec3b& b = bgr.at<cv::Vec3b>(y0, x1);
  const cv::Vec3b& c = bgr.at<cv::Vec3b>(y1, x0);
  const cv::Vec3b& d = bgr.at<cv::Vec3b>(y1, x1);
  Eigen::Vector3d out;
  for (int k = 0; k < 3; ++k) {
    const double top = a[k] + fx * (b[k] - a[k]);
    const double bottom = c[k] + fx * (d[k] - c[k]);
    out[k] = top + fy * (bottom - top);
  }
  return out;
}

}  // namespace sapmvs

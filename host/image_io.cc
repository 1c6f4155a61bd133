#include "sapmvs/image_io.h"

#include <gdal_priv.h>

#include <algorithm>
#include <cctype>
#include <memory>
#include <mutex>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sapmvs/error.h"

namespace sapmvs {
namespace {

void RegisterGdalOnce() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    // Readers probe files that may not be rasters; the error text reaches the
    // user through our own messages instead of GDAL's stderr handler.
    CPLSetErrorHandler(CPLQuietErrorHandler);
  });
}

std::string LowerExtension(const std::filesystem::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
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
  RegisterGdalOnce();
  if (!std::filesystem::is_regular_file(path)) {
    throw Error(path.string() + ": image file not found");
  }
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) throw Error(path.string() + ": not a readable image (" + CPLGetLastErrorMsg() + ")");
  return {ds->GetRasterXSize(), ds->GetRasterYSize()};
}

std::filesystem::path FindImageFile(const std::filesystem::path& folder, const std::string& name) {
  namespace fs = std::filesystem;
  if (fs::is_regular_file(folder / name)) return folder / name;
  if (!fs::is_directory(folder)) return {};
  const std::string stem = fs::path(name).stem().string();
  std::vector<fs::path> hits;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file() || !HasImageExtension(entry.path())) continue;
    const std::string s = entry.path().stem().string();
    if (s == name || s == stem) hits.push_back(entry.path());
  }
  if (hits.empty()) return {};
  // Deterministic choice when e.g. both a .tif and a .png copy exist.
  std::sort(hits.begin(), hits.end());
  return hits.front();
}

cv::Mat LoadImage(const BlockImage& image) {
  if (!std::filesystem::is_regular_file(image.path)) {
    throw Error(image.path.string() + ": image file not found (image '" + image.name + "')");
  }
  cv::Mat pixels = cv::imread(image.path.string(), cv::IMREAD_COLOR);
  if (pixels.empty()) {
    throw Error(image.path.string() + ": cannot decode image (expected 8-bit RGB or grey)");
  }
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

}  // namespace sapmvs

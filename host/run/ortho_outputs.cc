#include "run/ortho_outputs.h"

#include <algorithm>
#include <future>
#include <opencv2/imgproc.hpp>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/world_file.h"
#include "util/image_codec.h"

namespace sapmvs {

void WriteOrthoOutputs(const TrueOrtho& ortho, const std::filesystem::path& out) {
  const GeoRaster& grid = ortho.grid;
  // The GeoTIFF's compression and the PNG's share nothing: side by side.
  std::future<void> tif = std::async(
      std::launch::async, [&] { WriteColorGeoTiff(out / "ortho.tif", grid, ortho.rgba); });

  const int factor = std::max(
      1, (std::max(grid.width, grid.height) + kOrthoPictureMaxSide - 1) / kOrthoPictureMaxSide);
  // Averaged over factor x factor cells with alpha as a weight, so that
  // empty cells do not darken the edges of what is there.
  const cv::Size size((grid.width + factor - 1) / factor, (grid.height + factor - 1) / factor);
  cv::Mat bgra(size, CV_8UC4, cv::Scalar::all(0));
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) {
      double sum[4] = {0, 0, 0, 0};
      for (int y = r * factor; y < std::min(grid.height, (r + 1) * factor); ++y) {
        for (int x = c * factor; x < std::min(grid.width, (c + 1) * factor); ++x) {
          const uint8_t* p = &ortho.rgba[4 * (static_cast<size_t>(y) * grid.width + x)];
          for (int k = 0; k < 3; ++k) sum[k] += p[k] * p[3];
          sum[3] += p[3];
        }
      }
      if (sum[3] == 0) continue;
      cv::Vec4b& q = bgra.at<cv::Vec4b>(r, c);
      for (int k = 0; k < 3; ++k) q[2 - k] = cv::saturate_cast<uint8_t>(sum[k] / sum[3]);
      q[3] = cv::saturate_cast<uint8_t>(sum[3] / (factor * factor));
    }
  }
  const std::filesystem::path png = out / "ortho.png";
  const std::vector<unsigned char> bytes = EncodeImage(bgra, ImageEncoding::kPng, png.string());
  WriteBytesAtomically(png, bytes.data(), bytes.size());
  WriteWorldFile(out / "ortho.pgw", grid.origin_x, grid.origin_y, grid.cell_size * factor);
  tif.get();
}

}  // namespace sapmvs

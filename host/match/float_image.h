#pragma once
// A single-channel float image as the patch kernels see it (a view, not
// owned), and bilinear sampling of it in double precision: the reference that
// kernels/bilinear_sample.cl and the NCC kernels' sample_image are tested
// against, and what the CPU backend samples with. Pixel (0, 0) is the centre
// of the top-left pixel; a position is valid iff 0 <= x <= width - 1 and
// 0 <= y <= height - 1, and gives NaN otherwise (see the kernel file for the
// full policy, which every implementation shares).

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

// Shape of a row-major single-channel float image.
struct ImageLayout {
  int width = 0;      // Pixels, 1 to kMaxImageSide.
  int height = 0;     // Pixels, 1 to kMaxImageSide.
  int row_pitch = 0;  // Elements from one row start to the next, >= width.

  // Elements a buffer must hold: (height - 1) * row_pitch + width.
  size_t RequiredElements() const;
  // Throws Error naming `what` unless the layout is usable.
  void Validate(const char* what) const;
};

// A host image, not owned.
struct FloatImageView {
  const float* data = nullptr;
  ImageLayout layout;
};

// Bilinear value of `image` at (x, y), NaN outside; for callers that have
// validated the layout and the data already (the NCC reference samples every
// pixel of a patch this way, and a check per sample would dominate its time).
inline double BilinearSampleUnchecked(const FloatImageView& image, double x, double y) {
  const ImageLayout& layout = image.layout;
  if (!(x >= 0.0 && y >= 0.0 && x <= layout.width - 1 && y <= layout.height - 1)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  // Same cell clamping as the kernel; see kernels/bilinear_sample.cl.
  const int x0 = std::min(static_cast<int>(x), std::max(layout.width - 2, 0));
  const int y0 = std::min(static_cast<int>(y), std::max(layout.height - 2, 0));
  const int x1 = std::min(x0 + 1, layout.width - 1);
  const int y1 = std::min(y0 + 1, layout.height - 1);
  const double fx = x - x0;
  const double fy = y - y0;
  const float* row0 = image.data + static_cast<size_t>(y0) * static_cast<size_t>(layout.row_pitch);
  const float* row1 = image.data + static_cast<size_t>(y1) * static_cast<size_t>(layout.row_pitch);
  const double top = (1.0 - fx) * row0[x0] + fx * row0[x1];
  const double bottom = (1.0 - fx) * row1[x0] + fx * row1[x1];
  return (1.0 - fy) * top + fy * bottom;
}

// The kernel's twin in double precision, with exactly the same border and NaN
// policy. Throws Error for an invalid image.
double BilinearSampleReference(const FloatImageView& image, double x, double y);
std::vector<double> BilinearSampleReference(const FloatImageView& image,
                                            const std::vector<Eigen::Vector2f>& points);

}  // namespace sapmvs

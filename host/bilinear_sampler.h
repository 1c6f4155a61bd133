#pragma once
// Bilinear sampling of a single-channel float image at a batch of sub-pixel
// positions (kernels/bilinear_sample.cl), plus its double-precision reference.
// Pixel (0, 0) is the centre of the top-left pixel; a position is valid iff
// 0 <= x <= width - 1 and 0 <= y <= height - 1, and gives NaN otherwise (see
// the kernel file for the full policy, which both implementations share).

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "cl_runtime.h"
#include "sapmvs/kernel_limits.h"

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

struct BilinearSamplerOptions {
  // Work-items per work-group, passed to the kernel as -D WORK_GROUP_SIZE.
  // Must be >= 1; the device limits are checked at launch.
  int work_group_size = kDefaultWorkGroupSize;

  bool Check() const;
};

class BilinearSampler {
 public:
  // Builds the kernel (or takes it from the context's program cache). Throws
  // Error if !options.Check(). `context` must outlive the sampler.
  explicit BilinearSampler(ClContext& context,
                           const BilinearSamplerOptions& options = BilinearSamplerOptions());

  // values[i] = image at points[i]. Uploads, samples and reads back; blocking.
  std::vector<float> Sample(const FloatImageView& image,
                            const std::vector<Eigen::Vector2f>& points);

  // Device-resident variant for pipelines: `image` holds layout's pixels,
  // `points` num_points float2 (x, y), `values` receives num_points floats.
  // Validates everything, then enqueues without waiting; an empty batch
  // enqueues nothing and returns an empty event.
  ClEvent Sample(const ClBuffer& image, const ImageLayout& layout, const ClBuffer& points,
                 int num_points, ClBuffer& values);

  const BilinearSamplerOptions& options() const { return options_; }

 private:
  ClContext& context_;
  BilinearSamplerOptions options_;
  ClKernel kernel_;
};

// The kernel's twin in double precision, with exactly the same border and NaN
// policy. Throws Error for an invalid image.
double BilinearSampleReference(const FloatImageView& image, double x, double y);
std::vector<double> BilinearSampleReference(const FloatImageView& image,
                                            const std::vector<Eigen::Vector2f>& points);

}  // namespace sapmvs

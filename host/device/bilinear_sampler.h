#pragma once
// Bilinear sampling of a single-channel float image at a batch of sub-pixel
// positions (kernels/bilinear_sample.cl); its double-precision reference is in
// float_image.h.
// Pixel (0, 0) is the centre of the top-left pixel; a position is valid iff
// 0 <= x <= width - 1 and 0 <= y <= height - 1, and gives NaN otherwise (see
// the kernel file for the full policy, which both implementations share).

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "device/cl_runtime.h"
#include "match/float_image.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

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

}  // namespace sapmvs

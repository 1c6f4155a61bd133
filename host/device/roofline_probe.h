#pragma once
// The roofline probe (kernels/roofline_probe.cl): memory bandwidth by a plain
// copy, and the best NCC rate on contiguous integer windows, against which
// the matcher's kernels are judged (profiling/bench_ncc_scorer). Plus the
// double-precision twin of the window NCC the tests compare with.
#include <CL/cl.h>

#include <vector>

#include "device/bilinear_sampler.h"
#include "device/cl_runtime.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

struct RooflineProbeOptions {
  // mu: window side (-D PATCH_SIZE), odd, 3 to kMaxPatchSize.
  int patch_size = kDefaultPatchSize;
  // Work-items per work-group (-D WORK_GROUP_SIZE), >= 1.
  int work_group_size = kDefaultWorkGroupSize;
  // Empty when usable, else what was expected, naming the value.
  std::string Problem() const;
};

class RooflineProbe {
 public:
  // Throws Error for bad options; `context` must outlive the probe.
  RooflineProbe(ClContext& context, const RooflineProbeOptions& options = {});

  // dst = src over `n` float4; both buffers hold at least n float4.
  ClEvent Copy(const ClBuffer& src, ClBuffer& dst, int n);
  // NCC of the windows at corners[i] = (xa, ya, xb, yb) of two images of
  // the same layout (row_pitch == width). Blocking; `event` gets the kernel.
  std::vector<float> NccWindows(const FloatImageView& a, const FloatImageView& b,
                                const std::vector<cl_int4>& corners, ClEvent* event = nullptr);
  // Device-resident variant for benchmarks: enqueues without waiting.
  ClEvent NccWindows(const ClBuffer& a, const ClBuffer& b, int width, int height,
                     const ClBuffer& corners, int n, ClBuffer& scores);

  const RooflineProbeOptions& options() const { return options_; }

 private:
  ClContext& context_;
  RooflineProbeOptions options_;
  ClKernel copy_kernel_, ncc_kernel_;
};

// The kernel's twin in double: NaN for a window not wholly inside, or one
// whose variance sum is below kNccMinVariance * mu^2; else the clamped NCC.
double NccWindowReference(const FloatImageView& a, const FloatImageView& b, const cl_int4& corner,
                          int patch_size);

}  // namespace sapmvs

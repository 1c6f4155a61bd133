#pragma once
// Batched NCC scoring of patches on an OpenCL device (kernels/ncc_score.cl).
// The patch, its grid and the NaN rules are described in
// patch_kernel_types.h; the kernel's double-precision twin is
// NccScoreReference (ncc_score_reference.h). The matcher reaches this class
// only through PatchKernels (cl_patch_kernels.h).

#include <CL/cl.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <vector>

#include "device/bilinear_sampler.h"
#include "device/cl_runtime.h"
#include "match/ncc_score_reference.h"
#include "match/patch_kernel_types.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

// The build options of every program that includes ncc.cl (ncc_score.cl,
// patch_refine.cl and roofline_probe.cl): the NCC's variance floor, the
// sample weights, the patch side and the work-group size, so that the three
// score alike.
BuildOptions NccBuildOptions(int patch_size, int work_group_size, double sigma_color,
                             double sample_step = 1.0);

// ---------------------------------------------------------------------------

// A group resident on the device: every image packed into one buffer (one
// kernel argument however many images) with an int4 (offset in elements,
// width, height, row pitch) table, and the cameras. The scorer and the
// refiner each keep one for the group they work on.
struct NccDeviceGroup {
  ClBuffer images;
  ClBuffer image_table;
  ClBuffer cameras;
  int num_images = 0;
  // The host block `images` reads in place (NccGroup::pixels), kept alive
  // with it; empty when `images` holds a copy.
  std::shared_ptr<const float> pixels;
};

// Validates `group` and uploads it; throws before touching the device when the
// group is invalid or its pixels exceed the kernels' int offsets. Where the
// device shares the host's memory and the group's images lie in its
// `pixels` block exactly as the buffer lays them out, the buffer uses that
// block in place (a CPU device held a second copy of every image: 50 MB on
// Herz-Jesu-P8 at level 1).
NccDeviceGroup UploadNccGroup(ClContext& context, const NccGroup& group);

class NccScorer {
 public:
  // Builds the kernel (or takes it from the context's program cache). Throws
  // Error if !options.Check(). `context` must outlive the scorer.
  explicit NccScorer(ClContext& context, const NccScorerOptions& options = NccScorerOptions());

  // Validates and uploads the group; its images then stay on the device until
  // the next SetGroup. Blocking.
  void SetGroup(const NccGroup& group);
  // Uses a group already on the device, shared with other scorers and
  // refiners of the same context (one upload, however many patch sizes).
  void UseGroup(std::shared_ptr<const NccDeviceGroup> group);
  int num_images() const { return group_ ? group_->num_images : 0; }

  // scores[i] = NCC of pairs[i] (see NccPair), or NaN. Validates every index
  // and every patch (finite, unit normal within 1e-3) before enqueueing and
  // throws Error naming the first bad pair or patch. Blocking. If `event` is
  // given it receives the kernel's event (for profiling).
  std::vector<float> Score(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs,
                           ClEvent* event = nullptr);

  // values[k] = image `image` of the uploaded group at points[k], through
  // ncc.cl's sample_image (bilinear_at over the packed image table).
  std::vector<float> ProbeSamples(int image, const std::vector<Eigen::Vector2f>& points);

  const NccScorerOptions& options() const { return options_; }

 private:
  ClContext& context_;
  NccScorerOptions options_;
  ClKernel score_kernel_;
  ClKernel probe_kernel_;
  std::shared_ptr<const NccDeviceGroup> group_;
};

}  // namespace sapmvs

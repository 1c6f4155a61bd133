#pragma once
// Batched patch refinement on an OpenCL device (kernels/patch_refine.cl, a
// work-item per patch, on CPUs; patch_refine_group.cl, a work-group per patch,
// elsewhere: PatchRefinerOptions::layout); its double-precision twin is PatchRefineReference
// (patch_refine_reference.h), its options and results are in patch_kernel_types.h. For each patch
// (NccPatch: centre, unit normal, reference image) and its list of views, a fixed-iteration pattern
// search in-kernel optimises three parameters to maximise the mean NCC (ncc_scorer.h's score) over
// the views:
//   t      distance from the reference camera centre along the ray through the
//          initial centre (the centre stays on that ray: c = C + t r);
//   yaw    rotation of the normal about e_y, and
//   pitch  its elevation towards e_y, in the patch frame e_z = -r (towards the
//          reference camera), e_x = the reference x axis made orthogonal to
//          e_z, e_y = e_z x e_x:
//          n = cos(pitch) sin(yaw) e_x + sin(pitch) e_y + cos(pitch) cos(yaw) e_z.
// Each iteration polls p +- step_k on each parameter (order +t, -t, +yaw,
// -yaw, +pitch, -pitch, starting from the direction that moved last), moves
// to the first candidate that strictly beats the current mean NCC, and
// otherwise halves all steps, stopping early after max_halvings halvings. A candidate is invalid
// (never accepted) when any view's NCC is NaN or its normal lies more than
// max_angle_deg from the direction to the reference camera
// (cos(yaw) cos(pitch) < cos(max_angle_deg)).

#include <CL/cl.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <vector>

#include "device/cl_runtime.h"
#include "device/ncc_scorer.h"
#include "match/patch_kernel_types.h"
#include "match/patch_refine_reference.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {

class PatchRefiner {
 public:
  // Builds the kernel (or takes it from the program cache). Throws Error if
  // !options.Check(). `context` must outlive the refiner.
  explicit PatchRefiner(ClContext& context,
                        const PatchRefinerOptions& options = PatchRefinerOptions());

  // Validates and uploads the group (as NccScorer::SetGroup). Blocking.
  void SetGroup(const NccGroup& group);
  // Uses a group already uploaded (see NccScorer::UseGroup); `cameras` are
  // its host cameras, for validation.
  void UseGroup(std::shared_ptr<const NccDeviceGroup> group, std::vector<NccCamera> cameras);
  int num_images() const { return group_ ? group_->num_images : 0; }

  // Refines patches[i] against views[i]. Validates everything first (see
  // ValidatePatchRefineBatch) and throws Error naming the first bad patch or
  // view before enqueueing. Blocking.
  std::vector<RefinedPatch> Refine(const std::vector<NccPatch>& patches,
                                   const std::vector<std::vector<int>>& views,
                                   ClEvent* event = nullptr);

  const PatchRefinerOptions& options() const { return options_; }
  // options().layout resolved for the device (never kAuto).
  RefineLayout layout() const {
    return per_group_ ? RefineLayout::kPatchPerGroup : RefineLayout::kPatchPerItem;
  }

 private:
  ClContext& context_;
  PatchRefinerOptions options_;
  bool per_group_ = false;  // options_.layout resolved for the device
  int local_size_ = 0;      // work-items per work-group
  ClKernel kernel_;
  std::shared_ptr<const NccDeviceGroup> group_;
  std::vector<NccCamera> host_cameras_;
};

}  // namespace sapmvs

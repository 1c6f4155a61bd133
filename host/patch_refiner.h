#pragma once
// Batched patch refinement (kernels/patch_refine.cl), plus its double-precision
// reference. For each patch (NccPatch: centre, unit normal, reference image)
// and its list of views, a fixed-iteration pattern search in-kernel optimises
// three parameters to maximise the mean NCC (ncc_scorer.h's score) over the
// views:
//   t      distance from the reference camera centre along the ray through the
//          initial centre (the centre stays on that ray: c = C + t r);
//   yaw    rotation of the normal about e_y, and
//   pitch  its elevation towards e_y, in the patch frame e_z = -r (towards the
//          reference camera), e_x = the reference x axis made orthogonal to
//          e_z, e_y = e_z x e_x:
//          n = cos(pitch) sin(yaw) e_x + sin(pitch) e_y + cos(pitch) cos(yaw) e_z.
// Each iteration scores p +- step_k on each parameter (order +t, -t, +yaw,
// -yaw, +pitch, -pitch), moves to the best candidate if it strictly beats the
// current mean NCC, and otherwise halves all steps, stopping early after
// max_halvings halvings. A candidate is invalid
// (never accepted) when any view's NCC is NaN or |yaw| or |pitch| exceeds
// max_angle_deg.

#include <CL/cl.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <vector>

#include "cl_runtime.h"
#include "ncc_scorer.h"
#include "sapmvs/kernel_limits.h"

namespace sapmvs {

// One refined patch as the kernel writes it (48 bytes, 3 x float4).
struct RefinedPatchOut {
  cl_float4 center;  // xyz: refined centre; w: mean NCC over the views (NaN: none valid).
  cl_float4 normal;  // xyz: refined unit normal; w: 0.
  cl_float4 params;  // x: t - t0 in footprints of the start; y: yaw; z: pitch (radians);
                     // w: number of accepted moves.
};
static_assert(sizeof(RefinedPatchOut) == 48, "RefinedPatchOut must match the kernel's struct");

struct PatchRefinerOptions {
  // μ: samples per side of the patch grid (-D PATCH_SIZE). Odd, 3 to kMaxPatchSize.
  int patch_size = kDefaultPatchSize;
  // Work-items per work-group (-D WORK_GROUP_SIZE), >= 1.
  int work_group_size = kDefaultWorkGroupSize;
  // Search rounds, each scoring 6 candidates; 0 to kMaxRefineIterations.
  int iterations = kDefaultRefineIterations;
  // Stop after the steps were halved this many times (converged); >= 1.
  int max_halvings = kDefaultRefineHalvings;
  // Initial step of t, in footprints (depth / f of the reference camera at
  // the initial centre); finite and > 0.
  double depth_step = kDefaultRefineDepthStep;
  // Initial step of yaw and pitch, in degrees; finite, > 0 and <= 45.
  double angle_step_deg = kDefaultRefineAngleStepDeg;
  // Largest |yaw| and |pitch| a candidate may have, in degrees; (0, 89].
  double max_angle_deg = kDefaultRefineMaxAngleDeg;
  // Sample weights of the NCC (NccScorerOptions::sigma_color); finite, >= 0
  // (0 = plain NCC).
  double sigma_color = 0.0;

  // Logs the first failing condition to stderr and returns false.
  bool Check() const;
};

// One refined patch, host side.
struct RefinedPatch {
  NccPatch patch;                  // Refined centre and normal; same reference.
  float score = 0.0f;              // Mean NCC over the views; NaN if never valid.
  std::vector<float> view_scores;  // NCC per view, in the order given.
  float depth_offset = 0.0f;       // t - t0, in footprints of the start.
  float yaw = 0.0f;                // Radians.
  float pitch = 0.0f;              // Radians.
  int moves = 0;                   // Accepted moves.
};

// The reference's result, in double.
struct RefinedPatchReference {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double score = 0.0;
  std::vector<double> view_scores;
  double depth_offset = 0.0;
  double yaw = 0.0;
  double pitch = 0.0;
  int moves = 0;
  // Smallest gap, over every decision of the search, between the winning
  // score (the current one when nothing improved) and the best other valid
  // score. Where it is above float32 noise the kernel takes the same path.
  double decision_margin = 0.0;
};

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

 private:
  ClContext& context_;
  PatchRefinerOptions options_;
  ClKernel kernel_;
  std::shared_ptr<const NccDeviceGroup> group_;
  std::vector<NccCamera> host_cameras_;
};

// Throws Error unless: the patches pass ValidateNccBatch; views.size() ==
// patches.size(); each list has 1 to kMaxViews distinct views in the group,
// none the patch's reference; each normal faces the reference camera
// (n . (C - c) > 0, which also excludes c == C).
void ValidatePatchRefineBatch(const std::vector<NccPatch>& patches,
                              const std::vector<std::vector<int>>& views,
                              const std::vector<NccCamera>& cameras);

// The kernel's twin in double (from the same float inputs): same
// parameterisation, step schedule and tie rules; each candidate is scored by
// NccScoreReference.
std::vector<RefinedPatchReference> PatchRefineReference(const NccGroup& group,
                                                        const std::vector<NccPatch>& patches,
                                                        const std::vector<std::vector<int>>& views,
                                                        const PatchRefinerOptions& options);

}  // namespace sapmvs

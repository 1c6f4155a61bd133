#pragma once
// The patch refinement (patch_refiner.h describes the search) in double
// precision from the same float inputs as kernels/patch_refine.cl: same
// parameterisation, step schedule and tie rules, each candidate scored by
// NccScoreReference. What the kernel is tested against, and what the CPU
// backend (reference_patch_kernels.h) refines with.

#include <Eigen/Core>

#include <vector>

#include "match/patch_kernel_types.h"

namespace sapmvs {

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
  int evaluations = 0;  // Candidates scored, the start included.
  // Smallest gap, over every decision of the search, between a candidate's
  // score and the current score it was compared with. Where it is above
  // float32 noise the kernel takes the same path.
  double decision_margin = 0.0;
};

// Refines patches[i] against views[i]. Validates the options, the group and
// the batch first (throws Error naming the first fault). Patches are refined
// in parallel (OpenMP).
std::vector<RefinedPatchReference> PatchRefineReference(const NccGroup& group,
                                                        const std::vector<NccPatch>& patches,
                                                        const std::vector<std::vector<int>>& views,
                                                        const PatchRefinerOptions& options);

}  // namespace sapmvs

#pragma once
// Evaluates batches of candidate patches on the device, the same way for
// seeds and for every propagation wave (method.md 3.5, 3.6, 4.1): pick the views a
// candidate is visible in, keep those whose NCC reaches threshold_before,
// refine depth and normal in-kernel, keep the views whose NCC then reaches
// threshold, and accept the patch when they are at least min_image_num - 1.
// In sapmvs mode an accepted patch is then scored at the adaptive sizes,
// largest first (21, 15, 11, 7), each size one launch for the whole batch,
// and takes the largest size at which it still passes; only a patch with a
// view at least 2 max_angle_deg from its reference is tried at the larger
// sizes (narrow views do not pin a large plane down). Each size first
// polishes the patch at that size (a short refinement, one launch per size):
// the 7 x 7 window constrains the normal too loosely to extrapolate it over
// 21 pixels. Only patches whose unpolished plane already reaches
// threshold_before at that size, over the window and in its border
// sub-windows, are polished (PMVS's rule before optimisation; it skips about
// three quarters of the polishing, which most large patches fail anyway). A size
// is only taken when, in addition, the polished plane scores >= threshold in
// each of the 8 window_size sub-windows along the patch border (corners and
// edge midpoints): a large window that straddles a roof edge passes on its
// dominant part alone, and would emit roof-height points over the ground
// beside it (on the city preset the test raised the share within 1 m of the
// LiDAR from 54.5 % to 70.8 %).
#include <Eigen/Core>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "match/group_data.h"
#include "match/patch_kernels.h"
#include "sapmvs/match/match_stats.h"
#include "sapmvs/match/matcher_options.h"

namespace sapmvs {

struct PatchCandidate {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // local frame
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int ref = -1;
  // Expansion candidates: the plane of the patch they grew from. The refined
  // patch must stay within depth_tolerance footprints of it, else the
  // refinement jumped to another surface (or a false match) and the
  // expansion stops there; seeds (no parent) are not constrained.
  bool has_parent = false;
  Eigen::Vector3d parent_center = Eigen::Vector3d::Zero();
  Eigen::Vector3d parent_normal = Eigen::Vector3d::UnitZ();
  float parent_score = 0;  // the parent's mean NCC (AcceptedPatch::score)
};

struct AcceptedPatch {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  int ref = -1;
  std::vector<int> views;  // photo-consistent views, reference excluded
  float score = 0;         // mean NCC over `views` at the accepted size
  int size = 0;            // side of the accepted patch, pixels
};

// The sample grid that scores a window of `side` pixels: `samples` per side
// (odd), `step` pixels apart, spanning the side end to end. A side up to
// window_size samples every pixel; a larger one the fewest samples that keep
// the spacing at most max_step (MatcherOptions::adaptive_sample_step).
struct WindowGrid {
  int samples = 0;
  double step = 1.0;
};
WindowGrid SampledWindow(int side, int window_size, double max_step);

// The kernel variants (one program each) an engine with these options
// launches: the scores at window_size and at each larger adaptive size, the
// refinement, and each size's polish; and in sapmvs mode with pmvs_passes
// those of their engine (PmvsPassOptions).
struct EngineKernels {
  std::vector<NccScorerOptions> scorers;
  std::vector<PatchRefinerOptions> refiners;
};
EngineKernels EngineKernelVariants(const MatcherOptions& options);

// True when image `camera` sees the plane (c, n) at most view angle off its
// normal (cos_max: the cosine of view_angle_deg).
bool Faces(const Camera& camera, const Eigen::Vector3d& c, const Eigen::Vector3d& n,
           double cos_max);
// True when c lies in front of `camera`, inside its image by `margin`
// pixels, and the camera faces the plane (c, n) (Faces): an image a patch
// there may take as a view.
bool SeesPatch(const Camera& camera, const Eigen::Vector3d& c, const Eigen::Vector3d& n,
               double cos_max, double margin);

// The options that evaluate the candidates of sapmvs mode's last passes
// (MatcherOptions::pmvs_passes) as pmvs mode does: plain NCC at window_size,
// no polish, within pmvs_pass_view_angle_deg.
MatcherOptions PmvsPassOptions(const MatcherOptions& options);

class PatchEngine {
 public:
  // What the engine's patches are for.
  enum class Role {
    kPatches,
    // Sapmvs mode's pmvs passes (PmvsPassOptions): their one-cell patches
    // are not refit and the filter does not judge their planes (its
    // patch-support test), so their depth must be pinned by their own
    // views: one at least 2 max_angle_deg from the reference, as for the
    // adaptive patches' larger sizes. On `campus` (strips 50 m apart at
    // 700 m) the kept points of one-cell patches whose views met at 10-30
    // degrees were 47 % within 0.5 m of the truth, the adaptive patches' 83 %.
    kOneCellPass,
  };
  // Hands `group` to `kernels` (PatchKernels::SetGroup) until the engine is
  // destroyed; both must outlive the engine.
  PatchEngine(PatchKernels& kernels, const MatchGroupData& group, const MatcherOptions& options,
              Role role = Role::kPatches);
  ~PatchEngine();
  PatchEngine(const PatchEngine&) = delete;
  PatchEngine& operator=(const PatchEngine&) = delete;

  // One result per candidate, in order; nullopt = rejected. A candidate's
  // result does not depend on the others in the batch, so a large batch is
  // evaluated as two halves on two threads: while one half's host steps run,
  // the other half's kernels keep the device busy, and on an OpenCL device
  // the two halves' kernels run together (ClContext::QueueLease). A batch
  // whose candidates all have a parent starts its refinement at the
  // expansion steps (kExpansionRefineDepthStep).
  std::vector<std::optional<AcceptedPatch>> Evaluate(const std::vector<PatchCandidate>& candidates);

  // NCC of patches (centre, normal, ref) against `view`, window_size grid:
  // for edge matching. NaN where undefined.
  std::vector<float> Score(const std::vector<NccPatch>& patches, const std::vector<NccPair>& pairs);

  // Kernel launches, items and device seconds so far (seconds are 0 without
  // profiling).
  const std::map<std::string, KernelTime>& kernel_times() const { return kernel_times_; }

 private:
  // A plane tried at a larger patch size, with the views it is scored in.
  struct LargePlane {
    Eigen::Vector3d center, normal;
    int ref;
    const std::vector<int>* views;
  };
  // Per plane: whether each of the 8 window_size sub-windows at the corners
  // and edge midpoints of a size x size patch scores >= threshold, averaged
  // over the plane's views (sub-windows without texture count as fitting).
  std::vector<bool> CornersFit(int size, const std::vector<LargePlane>& planes, double threshold);
  // The patches of `open` (indices into `results`) worth polishing at
  // `size`, with the views to polish each with; the others go to `rejected`.
  std::vector<int> WorthPolishing(int size, const std::vector<int>& open,
                                  const std::vector<std::optional<AcceptedPatch>>& results,
                                  std::vector<std::vector<int>>* views, std::vector<int>* rejected);
  bool OnParentPlane(const PatchCandidate& candidate, const Eigen::Vector3d& center) const;
  // True when some pair of the reference and `views` meets at x at an angle
  // in (max_angle_deg, view_angle_deg); with from_ref, some pair of the
  // reference and a view at an angle in (2 max_angle_deg, view_angle_deg).
  bool WideEnough(const Eigen::Vector3d& x, int ref, const std::vector<int>& views,
                  bool from_ref = false) const;
  std::vector<int> VisibleViews(const Eigen::Vector3d& center, const Eigen::Vector3d& normal,
                                int ref, int half) const;
  std::vector<std::optional<AcceptedPatch>> EvaluateBatch(
      const std::vector<PatchCandidate>& candidates);
  std::vector<float> ScoreAt(int size, const std::vector<NccPatch>& patches,
                             const std::vector<NccPair>& pairs);
  // launch_mutex_, locked, unless the kernels take concurrent launches.
  std::unique_lock<std::mutex> LaunchLock();
  void Count(const std::string& kernel, int patch_size, long items, double ncc_evaluations,
             double seconds);
  std::vector<RefinedPatch> RefineWith(const PatchRefinerOptions& options,
                                       const std::vector<NccPatch>& patches,
                                       const std::vector<std::vector<int>>& views);

  PatchKernels& kernels_;
  const MatchGroupData& group_;
  const MatcherOptions& options_;
  const Role role_;
  PatchRefinerOptions refine_options_;
  // For a batch of expansion candidates (kExpansionRefineDepthStep).
  PatchRefinerOptions expansion_options_;
  std::map<int, PatchRefinerOptions> polish_options_;  // by patch side (sapmvs)
  // The group's view-only images (MatchImage::reference false), which
  // VisibleViews may add to widen a patch's angle; none in a one-group run.
  std::vector<int> view_only_images_;
  std::map<std::string, KernelTime> kernel_times_;
  // The halves of Evaluate launch from two threads. launch_mutex_ is held
  // for each launch unless the kernels take concurrent launches (the OpenCL
  // backend, whose launches then run together); count_mutex_ for each count.
  std::mutex launch_mutex_;
  std::mutex count_mutex_;
};

}  // namespace sapmvs

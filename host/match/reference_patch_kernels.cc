#include "match/reference_patch_kernels.h"

#include <omp.h>

#include <chrono>
#include <string>

#include "match/ncc_score_reference.h"
#include "match/patch_refine_reference.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

class ReferencePatchKernels : public PatchKernels {
 public:
  explicit ReferencePatchKernels(const PatchKernelsOptions& options) : profile_(options.profile) {
    const std::string threads = std::to_string(omp_get_max_threads());
    device_.description = "CPU reference (double precision, " + threads + " OpenMP threads)";
    device_.name = kReferenceDevice;
    device_.vendor = "sapmvs";
    device_.platform = "none (no OpenCL)";
    device_.type = "CPU";
  }

  const KernelDevice& device() const override { return device_; }

  void SetGroup(const NccGroup& group) override {
    ClearGroup();
    group.Validate();
    group_ = group;
  }

  void ClearGroup() override { group_ = NccGroup(); }

  std::vector<float> Score(const NccScorerOptions& options, const std::vector<NccPatch>& patches,
                           const std::vector<NccPair>& pairs, double* seconds) override {
    CheckGroup("Score");
    if (const std::string problem = options.Problem(); !problem.empty()) {
      throw Error("NccScorerOptions: expected " + problem);
    }
    const auto start = std::chrono::steady_clock::now();
    const std::vector<double> scores =
        NccScoreReference(group_, patches, pairs, options.patch_size, nullptr, options.sigma_color,
                          options.sample_step);
    std::vector<float> out(scores.begin(), scores.end());
    Time(start, seconds);
    return out;
  }

  std::vector<RefinedPatch> Refine(const PatchRefinerOptions& options,
                                   const std::vector<NccPatch>& patches,
                                   const std::vector<std::vector<int>>& views,
                                   double* seconds) override {
    CheckGroup("Refine");
    const auto start = std::chrono::steady_clock::now();
    const std::vector<RefinedPatchReference> refined =
        PatchRefineReference(group_, patches, views, options);
    std::vector<RefinedPatch> out(refined.size());
    for (size_t i = 0; i < refined.size(); ++i) {
      const RefinedPatchReference& r = refined[i];
      RefinedPatch& o = out[i];
      o.patch = MakeNccPatch(r.center, r.normal, patches[i].reference);
      o.score = static_cast<float>(r.score);
      o.view_scores.assign(r.view_scores.begin(), r.view_scores.end());
      o.depth_offset = static_cast<float>(r.depth_offset);
      o.yaw = static_cast<float>(r.yaw);
      o.pitch = static_cast<float>(r.pitch);
      o.moves = r.moves;
      o.evaluations = r.evaluations;
    }
    Time(start, seconds);
    return out;
  }

 private:
  void CheckGroup(const char* call) const {
    if (group_.images.empty()) {
      throw Error(std::string("PatchKernels::") + call + " called before SetGroup");
    }
  }

  void Time(std::chrono::steady_clock::time_point start, double* seconds) const {
    if (seconds == nullptr) return;
    *seconds = profile_
                   ? std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                   : 0.0;
  }

  bool profile_ = false;
  KernelDevice device_;
  NccGroup group_;
};

}  // namespace

std::unique_ptr<PatchKernels> MakeReferencePatchKernels(const PatchKernelsOptions& options) {
  return std::make_unique<ReferencePatchKernels>(options);
}

}  // namespace sapmvs

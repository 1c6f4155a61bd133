#include "device/cl_patch_kernels.h"

#include <algorithm>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>

#include "device/cl_runtime.h"
#include "device/ncc_scorer.h"
#include "device/patch_refiner.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/parallel_for.h"
#include "sapmvs/util/thread_count.h"

namespace sapmvs {
namespace {

// One scorer per distinct NccScorerOptions, one refiner per distinct
// PatchRefinerOptions (each is a program built with those -D options).
using ScorerKey = std::tuple<int, int, double, double>;
using RefinerKey =
    std::tuple<int, int, RefineLayout, int, int, double, double, double, double, double>;

ScorerKey KeyOf(const NccScorerOptions& o) {
  return {o.patch_size, o.work_group_size, o.sigma_color, o.sample_step};
}

RefinerKey KeyOf(const PatchRefinerOptions& o) {
  return {o.patch_size, o.work_group_size, o.layout,        o.iterations,  o.max_halvings,
          o.depth_step, o.angle_step_deg,  o.max_angle_deg, o.sigma_color, o.sample_step};
}

double Seconds(const ClEvent& event) {
  return event.profiling() ? 1e-9 * static_cast<double>(event.DeviceTimeNs()) : 0.0;
}

class ClPatchKernels : public PatchKernels {
 public:
  ClPatchKernels(std::unique_ptr<ClContext> owned, ClContext& context)
      : owned_(std::move(owned)), context_(context) {
    const DeviceInfo& d = context_.device();
    device_.description = d.Describe();
    device_.name = d.name;
    device_.vendor = d.vendor;
    device_.platform = d.platform_name + " (" + d.platform_version + ")";
    device_.type = DeviceTypeName(d.type);
  }

  const KernelDevice& device() const override { return device_; }

  double PeakDeviceBytes() const override { return sapmvs::PeakDeviceBytes(); }
  void ResetPeakDeviceBytes() override { sapmvs::ResetPeakDeviceBytes(); }

  void SetGroup(const NccGroup& group) override {
    ClearGroup();  // first, so that the old group's buffers are freed before the upload
    group_ = std::make_shared<const NccDeviceGroup>(UploadNccGroup(context_, group));
    cameras_ = group.cameras;
  }

  void ClearGroup() override {
    // The scorers and refiners hold the group too; new ones are made on first
    // use, from the programs the context has cached.
    scorers_.clear();
    refiners_.clear();
    group_.reset();
    cameras_.clear();
  }

  void Prepare(const std::vector<NccScorerOptions>& scorers,
               const std::vector<PatchRefinerOptions>& refiners) override {
    // The context caches each program for the scorers and refiners that
    // later launches make; these are only built to fill that cache, on
    // several threads: NVIDIA's driver took 1 s or more per program on a
    // cold cache, one after the other (Herz-Jesu-P8's first run on an H200).
    std::vector<std::function<void()>> builds;
    for (const NccScorerOptions& o : scorers) {
      builds.emplace_back([this, o] { NccScorer scorer(context_, o); });
    }
    for (const PatchRefinerOptions& o : refiners) {
      builds.emplace_back([this, o] { PatchRefiner refiner(context_, o); });
    }
    // MatchGroup's thread loads the images meanwhile: one of the host's
    // threads fewer (so none more on two cores).
    ParallelFor(
        static_cast<long>(builds.size()),
        [&builds](long i) {
          try {
            builds[static_cast<size_t>(i)]();
          } catch (const std::exception&) {  // the launch reports it
          }
        },
        /*block=*/1, std::max(1, HostThreadCount() - 1));
  }

  bool ConcurrentLaunches() const override { return true; }

  std::vector<float> Score(const NccScorerOptions& options, const std::vector<NccPatch>& patches,
                           const std::vector<NccPair>& pairs, double* seconds) override {
    const ClContext::QueueLease lease = context_.LeaseQueue();
    ClEvent event;
    std::vector<float> scores = ScorerFor(options).Score(patches, pairs, &event);
    if (seconds != nullptr) *seconds = Seconds(event);
    return scores;
  }

  std::vector<RefinedPatch> Refine(const PatchRefinerOptions& options,
                                   const std::vector<NccPatch>& patches,
                                   const std::vector<std::vector<int>>& views,
                                   double* seconds) override {
    const ClContext::QueueLease lease = context_.LeaseQueue();
    ClEvent event;
    std::vector<RefinedPatch> refined = RefinerFor(options).Refine(patches, views, &event);
    if (seconds != nullptr) *seconds = Seconds(event);
    return refined;
  }

 private:
  // Under lookup_mutex_: launches on two threads may make the first of a kind.
  NccScorer& ScorerFor(const NccScorerOptions& options) {
    std::lock_guard<std::mutex> lock(lookup_mutex_);
    if (!group_) throw Error("PatchKernels::Score called before SetGroup");
    std::unique_ptr<NccScorer>& scorer = scorers_[KeyOf(options)];
    if (!scorer) {
      auto made = std::make_unique<NccScorer>(context_, options);
      made->UseGroup(group_);
      scorer = std::move(made);
    }
    return *scorer;
  }

  PatchRefiner& RefinerFor(const PatchRefinerOptions& options) {
    std::lock_guard<std::mutex> lock(lookup_mutex_);
    if (!group_) throw Error("PatchKernels::Refine called before SetGroup");
    std::unique_ptr<PatchRefiner>& refiner = refiners_[KeyOf(options)];
    if (!refiner) {
      auto made = std::make_unique<PatchRefiner>(context_, options);
      made->UseGroup(group_, cameras_);
      refiner = std::move(made);
    }
    return *refiner;
  }

  std::unique_ptr<ClContext> owned_;
  ClContext& context_;
  KernelDevice device_;
  std::shared_ptr<const NccDeviceGroup> group_;
  std::vector<NccCamera> cameras_;
  std::map<ScorerKey, std::unique_ptr<NccScorer>> scorers_;
  std::map<RefinerKey, std::unique_ptr<PatchRefiner>> refiners_;
  std::mutex lookup_mutex_;
};

}  // namespace

std::unique_ptr<PatchKernels> MakeClPatchKernels(const PatchKernelsOptions& options) {
  DeviceOptions device_options;
  device_options.device = options.device;
  device_options.profile = options.profile;
  auto context = std::make_unique<ClContext>(device_options);
  ClContext& ref = *context;
  return std::make_unique<ClPatchKernels>(std::move(context), ref);
}

std::unique_ptr<PatchKernels> MakeClPatchKernels(ClContext& context) {
  return std::make_unique<ClPatchKernels>(nullptr, context);
}

}  // namespace sapmvs

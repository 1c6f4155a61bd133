#pragma once
// The wall between the matcher and the device: the operations the matcher
// launches on a batch of patches (score at a patch size, refine), behind one
// interface with two backends, the OpenCL kernels (cl_patch_kernels.h) and
// the double-precision CPU reference (reference_patch_kernels.h). Nothing on
// this side of the wall includes an OpenCL header, so the matcher builds and
// runs where no OpenCL platform is installed.

#include <memory>
#include <string>
#include <vector>

#include "match/patch_kernel_types.h"

namespace sapmvs {

// The device spec that selects the CPU reference (case-insensitive).
inline constexpr char kReferenceDevice[] = "reference";

struct PatchKernelsOptions {
  // "reference" = the CPU reference backend. Otherwise an OpenCL device: an
  // index or a name substring (the OpenCL runtime's DeviceOptions::device); "" =
  // SAPMVS_DEVICE from the environment if set (which may also say
  // "reference"), else the default OpenCL device.
  std::string device;
  // Time each launch: OpenCL queue profiling, or the reference's wall clock.
  bool profile = false;
};

// Where the kernels run, as report.json and the log name it.
struct KernelDevice {
  std::string description;  // one line, as `sapmvs devices` describes it
  std::string name;
  std::string vendor;
  std::string platform;  // platform name and version
  std::string type;      // "GPU", "CPU" or "other"
};

class PatchKernels {
 public:
  virtual ~PatchKernels() = default;

  virtual const KernelDevice& device() const = 0;

  // Makes `group` the images and cameras later calls refer to, until the
  // next SetGroup or ClearGroup: validates it (throws Error naming the image
  // at fault) and, on a device, uploads it. Its pixels must outlive that.
  virtual void SetGroup(const NccGroup& group) = 0;
  // Lets go of the group (and the device memory that holds it).
  virtual void ClearGroup() = 0;

  // Builds what launches with these options need (on a device, their
  // programs), so that the first launches need not wait for it. May run on
  // another thread while the caller makes no other call on this object;
  // failures are left for the launch that needs the program to report.
  virtual void Prepare(const std::vector<NccScorerOptions>& /*scorers*/,
                       const std::vector<PatchRefinerOptions>& /*refiners*/) {}

  // Device memory this backend holds, bytes, at its peak since
  // ResetPeakDeviceBytes (the group's images and the largest batch): what a
  // GPU must have free. 0 for the reference, whose memory is the host's.
  virtual double PeakDeviceBytes() const { return 0; }
  virtual void ResetPeakDeviceBytes() {}

  // True when Score and Refine may be called from two threads at once, whose
  // launches then run together.
  virtual bool ConcurrentLaunches() const { return false; }

  // scores[i] = NCC of pairs[i] at options.patch_size with options'
  // sample weights, NaN where undefined. Throws Error for bad options or a
  // bad batch (ValidateNccBatch) before any work. `seconds` (may be null)
  // receives the time the work took when profiling, else 0.
  virtual std::vector<float> Score(const NccScorerOptions& options,
                                   const std::vector<NccPatch>& patches,
                                   const std::vector<NccPair>& pairs, double* seconds) = 0;

  // Refines patches[i] against views[i] (patch_refiner.h describes the
  // search). Throws Error for bad options or a bad batch
  // (ValidatePatchRefineBatch) before any work. `seconds` as for Score.
  virtual std::vector<RefinedPatch> Refine(const PatchRefinerOptions& options,
                                           const std::vector<NccPatch>& patches,
                                           const std::vector<std::vector<int>>& views,
                                           double* seconds) = 0;
};

// True when `options` (or, without a device, SAPMVS_DEVICE) selects the CPU
// reference.
bool SelectsReference(const PatchKernelsOptions& options);

// What a device holds per patch of a batch and per (patch, view) pair, beyond
// the group's images: the planner's memory model (match_group.h MatcherMemory).
struct KernelBatchBytes {
  double per_patch = 0;  // the patch, its refined result and its view offset
  double per_pair = 0;   // the pair, its score and its view index
};
KernelBatchBytes PatchKernelBatchBytes();

}  // namespace sapmvs

#include "match/patch_kernels.h"

#include "match/device_spec.h"

namespace sapmvs {

bool SelectsReference(const PatchKernelsOptions& options) {
  return IsReferenceSpec(DeviceSpecFor(options.device));
}

KernelBatchBytes PatchKernelBatchBytes() {
  KernelBatchBytes bytes;
  // The refinement's buffers: the patches, their results and the view list
  // offsets; per view of a patch, the scoring's pair and score and the
  // refinement's view index and per-view score.
  bytes.per_patch = sizeof(NccPatch) + sizeof(RefinedPatchOut) + 4;
  bytes.per_pair = sizeof(NccPair) + 4 + 4;
  return bytes;
}

}  // namespace sapmvs

#include "device/make_patch_kernels.h"

#include "device/cl_patch_kernels.h"
#include "match/reference_patch_kernels.h"

namespace sapmvs {

std::unique_ptr<PatchKernels> MakePatchKernels(const PatchKernelsOptions& options) {
  if (SelectsReference(options)) return MakeReferencePatchKernels(options);
  return MakeClPatchKernels(options);
}

}  // namespace sapmvs

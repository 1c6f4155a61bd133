#include "make_patch_kernels.h"

#include "cl_patch_kernels.h"
#include "reference_patch_kernels.h"

namespace sapmvs {

std::unique_ptr<PatchKernels> MakePatchKernels(const PatchKernelsOptions& options) {
  if (SelectsReference(options)) return MakeReferencePatchKernels(options);
  return MakeClPatchKernels(options);
}

}  // namespace sapmvs

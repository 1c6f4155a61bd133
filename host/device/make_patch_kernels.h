#pragma once
// Chooses the matcher's backend. It lives with the OpenCL backend, the only
// layer that sees both backends; the matcher knows only PatchKernels.
#include <memory>

#include "match/patch_kernels.h"

namespace sapmvs {

// The backend `options` selects. The reference makes no OpenCL call at all;
// an OpenCL device that cannot be found throws NoDeviceError.
std::unique_ptr<PatchKernels> MakePatchKernels(const PatchKernelsOptions& options);

}  // namespace sapmvs

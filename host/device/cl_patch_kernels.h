#pragma once
// The OpenCL backend of PatchKernels: NccScorer and PatchRefiner on one
// context, one scorer per (patch size, sample weights) and one refiner per
// search, all sharing one upload of the group. No OpenCL type appears here,
// so the callers that pick a backend stay on the matcher's side of the wall.

#include <memory>

#include "match/patch_kernels.h"

namespace sapmvs {

class ClContext;

// A context of its own, chosen as DeviceOptions chooses (options.device must
// not select the reference). Throws NoDeviceError.
std::unique_ptr<PatchKernels> MakeClPatchKernels(const PatchKernelsOptions& options);

// On `context`, which must outlive the kernels (tests share one per process).
std::unique_ptr<PatchKernels> MakeClPatchKernels(ClContext& context);

}  // namespace sapmvs

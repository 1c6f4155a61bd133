#pragma once
// The CPU backend of PatchKernels: the kernels' double-precision references
// (ncc_score_reference.h, patch_refine_reference.h), parallel over the
// batch with OpenMP. It makes no OpenCL call, so `--device reference` runs the
// whole matcher where no OpenCL platform is installed; its results agree with
// a device's to float32 rounding, which can flip near-ties of the refinement
// and so move a few points (docs/devices.md gives the measured agreement).

#include <memory>

#include "match/patch_kernels.h"

namespace sapmvs {

std::unique_ptr<PatchKernels> MakeReferencePatchKernels(const PatchKernelsOptions& options);

}  // namespace sapmvs

#pragma once
// How many threads the tool uses: OpenMP and OpenCV on the host, and PoCL's
// CPU device. PoCL reads POCL_MAX_PTHREAD_COUNT once, when the OpenCL
// platform is loaded, so SetThreadCount() must come before any OpenCL call.

namespace sapmvs {

// `threads` > 0: at most that many threads on the host and in PoCL's CPU
// device (POCL_MAX_PTHREAD_COUNT is set, replacing the user's own). 0: all
// cores, the libraries' defaults (and OMP_NUM_THREADS or
// POCL_MAX_PTHREAD_COUNT when the user set them). Throws Error for a negative
// count.
void SetThreadCount(int threads);

// The threads the host's parallel loops use: SetThreadCount's count on every
// thread once it was given one, else OpenMP's maximum.
int HostThreadCount();

}  // namespace sapmvs

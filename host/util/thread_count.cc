#include "sapmvs/util/thread_count.h"

#include <omp.h>

#include <atomic>
#include <cstdlib>
#include <opencv2/core/utility.hpp>
#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// The count SetThreadCount was given, for every thread: omp_set_num_threads
// sets the calling thread's count only, and a thread started with
// std::thread (the kernels' builds, the tie points' SIFT) saw all cores.
std::atomic<int> g_thread_count{0};

}  // namespace

void SetThreadCount(int threads) {
  if (threads < 0) {
    throw Error("--threads " + std::to_string(threads) +
                ": expected 0 (all cores) or a positive number of threads");
  }
  if (threads == 0) return;
  g_thread_count.store(threads);
  omp_set_num_threads(threads);
  cv::setNumThreads(threads);
  // PoCL's pthread (CPU) device sizes its worker pool from this variable
  // when the platform is first loaded.
  ::setenv("POCL_MAX_PTHREAD_COUNT", std::to_string(threads).c_str(), 1);
}

int HostThreadCount() {
  const int set = g_thread_count.load();
  return set > 0 ? set : omp_get_max_threads();
}

}  // namespace sapmvs

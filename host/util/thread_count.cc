#include "sapmvs/util/thread_count.h"

#include <omp.h>

#include <cstdlib>
#include <opencv2/core/utility.hpp>
#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {

void SetThreadCount(int threads) {
  if (threads < 0) {
    throw Error("--threads " + std::to_string(threads) +
                ": expected 0 (all cores) or a positive number of threads");
  }
  if (threads == 0) return;
  omp_set_num_threads(threads);
  cv::setNumThreads(threads);
  // PoCL's pthread (CPU) device sizes its worker pool from this variable
  // when the platform is first loaded.
  ::setenv("POCL_MAX_PTHREAD_COUNT", std::to_string(threads).c_str(), 1);
}

int HostThreadCount() { return omp_get_max_threads(); }

}  // namespace sapmvs

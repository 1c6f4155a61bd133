#pragma once
// A parallel loop for the host work between device launches.
//
// OpenMP's idle workers spin for milliseconds after each parallel region
// (libgomp's GOMP_SPINCOUNT) on the cores that the OpenCL runtime's threads
// need for the next kernel. In propagation, which alternates short host loops
// with kernels, OpenMP there doubled libgomp's share of the CPU samples on
// the simulator's `city` (2.3 to 4.6 %). The threads here live for one call:
// starting one costs tens of microseconds, and after the loop nothing is
// left running.
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

#include "sapmvs/util/thread_count.h"

namespace sapmvs {

// Calls f(i) once for every i in [0, n), on up to HostThreadCount() threads
// (the caller's among them; fewer when max_threads > 0 is smaller), `block`
// consecutive indices at a time; calls
// for different i may run at once. When a call throws, the indices not yet
// started are skipped and the first exception is rethrown here, after every
// thread has stopped.
template <typename F>
void ParallelFor(long n, const F& f, long block = 16, int max_threads = 0) {
  long threads = std::min<long>(HostThreadCount(), (n + block - 1) / block);
  if (max_threads > 0) threads = std::min<long>(threads, max_threads);
  if (threads <= 1) {
    for (long i = 0; i < n; ++i) f(i);
    return;
  }
  std::atomic<long> next{0};
  std::mutex failed_mutex;
  std::exception_ptr failed;
  auto work = [&] {
    try {
      for (long b = next.fetch_add(block); b < n; b = next.fetch_add(block)) {
        for (long i = b, e = std::min(n, b + block); i < e; ++i) f(i);
      }
    } catch (...) {
      next.store(n);
      std::lock_guard<std::mutex> lock(failed_mutex);
      if (!failed) failed = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  try {
    for (long t = 1; t < threads; ++t) pool.emplace_back(work);
  } catch (const std::system_error&) {
    // No thread to be had (a process limit): the threads that did start,
    // and this one, share the loop.
  }
  work();
  for (std::thread& t : pool) t.join();
  if (failed) std::rethrow_exception(failed);
}

}  // namespace sapmvs

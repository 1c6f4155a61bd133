#pragma once
// A parallel loop for the host work between device launches.
//
// OpenMP's idle workers spin for milliseconds after each parallel region
// (libgomp's GOMP_SPINCOUNT) on the cores that the OpenCL runtime's threads
// need for the next kernel; in propagation, which alternates short host loops
// with kernels, that spinning cost more CPU than the loops saved. The threads
// here live for one call: starting one costs tens of microseconds, and after
// the loop nothing is left running.
#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "sapmvs/util/thread_count.h"

namespace sapmvs {

// Calls f(i) once for every i in [0, n), on up to HostThreadCount() threads
// (the caller's among them), `block` consecutive indices at a time. f must
// not throw; calls for different i may run at once.
template <typename F>
void ParallelFor(long n, const F& f, long block = 16) {
  const long threads = std::min<long>(HostThreadCount(), (n + block - 1) / block);
  if (threads <= 1) {
    for (long i = 0; i < n; ++i) f(i);
    return;
  }
  std::atomic<long> next{0};
  auto work = [&] {
    for (long b = next.fetch_add(block); b < n; b = next.fetch_add(block)) {
      for (long i = b, e = std::min(n, b + block); i < e; ++i) f(i);
    }
  };
  std::vector<std::thread> pool;
  for (long t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace sapmvs

#include "sapmvs/util/memory_use.h"

#include <sys/resource.h>
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <fstream>
#include <string>
#include <system_error>
#include <thread>

namespace sapmvs {

namespace {

// A "Name:   123 kB" line of /proc/self/status, in bytes; 0 when absent.
double ProcStatusBytes(const std::string& name) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.compare(0, name.size(), name) == 0 && line.size() > name.size() &&
        line[name.size()] == ':') {
      return 1024.0 * std::stod(line.substr(name.size() + 1));
    }
  }
  return 0;
}

// ReturnLargeBlocksToSystem's threshold; ScopedHeapReuse's, glibc's largest
// (HEAP_MAX_SIZE / 2 on 64-bit systems); glibc's default trim threshold.
constexpr int kLargeBlock = 2 << 20;
constexpr int kReuseUpTo = 32 << 20;
constexpr int kDefaultTrimThreshold = 128 << 10;

// The process's peak before the last reset (ResetPeakRss).
std::atomic<double> peak_before_reset{0};

}  // namespace

double PeakRssBytes() {
  // VmHWM follows ResetPeakRss; getrusage's ru_maxrss does not.
  const double hwm = ProcStatusBytes("VmHWM");
  if (hwm > 0) return hwm;
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return 1024.0 * static_cast<double>(u.ru_maxrss);  // Linux reports kilobytes
}

double CurrentRssBytes() { return ProcStatusBytes("VmRSS"); }

double ProcessPeakRssBytes() { return std::max(peak_before_reset.load(), PeakRssBytes()); }

bool ResetPeakRss() {
  peak_before_reset = ProcessPeakRssBytes();
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5" << std::flush;  // 5: reset the peak RSS (proc(5))
  return static_cast<bool>(f);
}

void ReturnLargeBlocksToSystem() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, kLargeBlock);
#endif
}

ScopedHeapReuse::ScopedHeapReuse() {
#if defined(__GLIBC__)
  // A free chunk above the trim threshold at the heap's top goes back too.
  mallopt(M_TRIM_THRESHOLD, kReuseUpTo);
  mallopt(M_MMAP_THRESHOLD, kReuseUpTo);
#endif
}

ScopedHeapReuse::~ScopedHeapReuse() {
  ReturnLargeBlocksToSystem();
#if defined(__GLIBC__)
  mallopt(M_TRIM_THRESHOLD, kDefaultTrimThreshold);
#endif
  ReleaseFreeMemory();
}

void RunWithHeapReuse(const std::function<void()>& work) {
  const ScopedHeapReuse reuse;
  std::exception_ptr failed;
  auto run = [&] {
    try {
      work();
    } catch (...) {
      failed = std::current_exception();
    }
  };
  try {
    std::thread(run).join();
  } catch (const std::system_error&) {  // no thread to be had: on this one
    run();
  }
  if (failed) std::rethrow_exception(failed);
}

bool UnwrittenMemoryIsFree() {
  // Linux counts private writable mappings against the data limit too
  // (since 4.7), reserved or written.
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit limit{};
    if (getrlimit(resource, &limit) != 0 || limit.rlim_cur != RLIM_INFINITY) return false;
  }
  std::ifstream f("/proc/sys/vm/overcommit_memory");
  int mode = -1;
  return static_cast<bool>(f >> mode) && mode != 2;
}

void ReleasePages(void* begin, void* end) {
#if defined(__linux__)
  const auto page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  const uintptr_t first = (reinterpret_cast<uintptr_t>(begin) + page - 1) / page * page;
  const uintptr_t last = reinterpret_cast<uintptr_t>(end) / page * page;
  // MADV_DONTNEED, not MADV_FREE: the pages must leave the RSS now, before
  // the next peak, not when the system runs short.
  if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_DONTNEED);
#else
  (void)begin;
  (void)end;
#endif
}

void ReleaseFreeMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace sapmvs

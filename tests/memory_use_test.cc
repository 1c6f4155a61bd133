#include "sapmvs/util/memory_use.h"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstring>
#include <fstream>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <thread>
#include <vector>

namespace sapmvs {
namespace {

constexpr size_t kBlock = 64u << 20;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitizerAllocator = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kSanitizerAllocator = true;
#else
constexpr bool kSanitizerAllocator = false;
#endif
#else
constexpr bool kSanitizerAllocator = false;
#endif

// Touches every page, so that the block is resident, and keeps the compiler
// from dropping the writes.
std::unique_ptr<char[]> TouchedBlock(size_t bytes = kBlock) {
  std::unique_ptr<char[]> p(new char[bytes]);
  std::memset(p.get(), 1, bytes);
  volatile char sink = p[bytes - 1];
  (void)sink;
  return p;
}

TEST(MemoryUse, PeakFollowsWhatIsTouchedAndResets) {
  const double now = CurrentRssBytes();
  if (now <= 0) GTEST_SKIP() << "this system does not report the RSS (/proc/self/status)";
  if (!ResetPeakRss()) GTEST_SKIP() << "this system cannot reset the peak RSS (clear_refs)";
  const double before = PeakRssBytes();
  {
    auto block = TouchedBlock();
    EXPECT_GE(CurrentRssBytes(), now + 0.9 * kBlock);
  }
  EXPECT_GE(PeakRssBytes(), before + 0.9 * kBlock);
  const double process_peak = ProcessPeakRssBytes();
  EXPECT_GE(process_peak, before + 0.9 * kBlock);
  if (kSanitizerAllocator) {
    GTEST_SKIP() << "the rest needs freed memory back in the system, which the address "
                    "sanitizer's allocator keeps in its quarantine";
  }
  // The block is freed: a new peak starts below it, and the process's stays.
  ReleaseFreeMemory();
  ASSERT_TRUE(ResetPeakRss());
  EXPECT_LT(PeakRssBytes(), process_peak - 0.5 * kBlock);
  EXPECT_GE(ProcessPeakRssBytes(), process_peak);
}

TEST(MemoryUse, LargeBlocksGoBackToTheSystemWhenFreed) {
  if (CurrentRssBytes() <= 0) GTEST_SKIP() << "this system does not report the RSS";
  if (kSanitizerAllocator) {
    GTEST_SKIP() << "the address sanitizer's allocator keeps freed memory in its quarantine";
  }
  ReturnLargeBlocksToSystem();
  // Freeing a 24 MiB block raised glibc's own threshold to its size (it
  // follows freed blocks up to 32 MiB), after which an 8 MiB block came from
  // the heap and stayed resident once freed.
  TouchedBlock(24u << 20).reset();
  constexpr size_t kMedium = 8u << 20;
  auto block = TouchedBlock(kMedium);
  const double held = CurrentRssBytes();
  block.reset();
  EXPECT_LE(CurrentRssBytes(), held - 0.9 * kMedium);
}

// A vector shrunk in place keeps the pages of its largest size resident until
// its tail is handed back; what it still holds, up to the last element on a
// partly kept page, stays as it was.
TEST(MemoryUse, ReleasedCapacityLeavesTheRssAndKeepsTheElements) {
  if (CurrentRssBytes() <= 0) GTEST_SKIP() << "this system does not report the RSS";
  std::vector<int64_t> v(kBlock / sizeof(int64_t));
  std::iota(v.begin(), v.end(), int64_t{0});
  const size_t kept = v.size() / 4 + 3;  // ends inside a page
  v.resize(kept);
  const double held = CurrentRssBytes();
  ReleaseUnusedCapacity(v);
  EXPECT_LE(CurrentRssBytes(), held - 0.7 * kBlock);
  for (size_t i = 0; i < kept; ++i) ASSERT_EQ(v[i], static_cast<int64_t>(i)) << "element " << i;
  v.resize(v.capacity(), -1);  // the released tail takes elements again
  EXPECT_EQ(v.back(), -1);
  EXPECT_EQ(v[kept - 1], static_cast<int64_t>(kept - 1));
}

// Inside the scope a freed 8 MiB block stays resident for the next one;
// at its end it goes back, and so do blocks freed after it.
TEST(MemoryUse, ScopedHeapReuseKeepsFreedBlocksUntilItEnds) {
  if (CurrentRssBytes() <= 0) GTEST_SKIP() << "this system does not report the RSS";
  if (kSanitizerAllocator) {
    GTEST_SKIP() << "the address sanitizer's allocator keeps freed memory in its quarantine";
  }
  ReturnLargeBlocksToSystem();
  constexpr size_t kMedium = 8u << 20;
  double held = 0;
  {
    const ScopedHeapReuse reuse;
    auto block = TouchedBlock(kMedium);
    held = CurrentRssBytes();
    block.reset();
    EXPECT_GE(CurrentRssBytes(), held - 0.1 * kMedium);
  }
  EXPECT_LE(CurrentRssBytes(), held - 0.9 * kMedium);
  auto block = TouchedBlock(kMedium);
  held = CurrentRssBytes();
  block.reset();
  EXPECT_LE(CurrentRssBytes(), held - 0.9 * kMedium);
}

// The work runs on another thread (ScopedHeapReuseKeepsFreedBlocksUntilItEnds
// covers the reuse), and what it throws arrives here.
TEST(MemoryUse, RunWithHeapReuseRunsOnAnotherThreadAndRethrows) {
  const std::thread::id caller = std::this_thread::get_id();
  std::thread::id ran_on = caller;
  RunWithHeapReuse([&] { ran_on = std::this_thread::get_id(); });
  EXPECT_NE(ran_on, caller);
  EXPECT_THROW(RunWithHeapReuse([] { throw std::runtime_error("from the work"); }),
               std::runtime_error);
}

// An address-space limit (a batch system's h_vmem) or a data limit
// (ulimit -d) counts every reserved page: under one, reserving costs what
// writing would.
TEST(MemoryUse, UnwrittenMemoryIsNotFreeUnderAnAddressSpaceOrDataLimit) {
  rlimit as{}, data{};
  ASSERT_EQ(getrlimit(RLIMIT_AS, &as), 0);
  ASSERT_EQ(getrlimit(RLIMIT_DATA, &data), 0);
  if (as.rlim_cur == RLIM_INFINITY && data.rlim_cur == RLIM_INFINITY) {
    std::ifstream f("/proc/sys/vm/overcommit_memory");
    int mode = -1;
    if (!(f >> mode)) GTEST_SKIP() << "this system does not say how it overcommits (/proc)";
    EXPECT_EQ(UnwrittenMemoryIsFree(), mode != 2) << "vm.overcommit_memory = " << mode;
  }
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    SCOPED_TRACE(resource == RLIMIT_AS ? "RLIMIT_AS" : "RLIMIT_DATA");
    rlimit saved{};
    ASSERT_EQ(getrlimit(resource, &saved), 0);
    // The largest finite limit: nothing this process maps can fail under it.
    rlimit limited = saved;
    limited.rlim_cur = RLIM_INFINITY - 1;
    if (saved.rlim_max != RLIM_INFINITY) limited.rlim_cur = saved.rlim_max;
    ASSERT_EQ(setrlimit(resource, &limited), 0);
    const bool free_under_limit = UnwrittenMemoryIsFree();
    ASSERT_EQ(setrlimit(resource, &saved), 0);
    EXPECT_FALSE(free_under_limit);
  }
}

}  // namespace
}  // namespace sapmvs

#include "sapmvs/util/memory_use.h"

#include <gtest/gtest.h>

#include <cstring>
#include <memory>

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
std::unique_ptr<char[]> TouchedBlock() {
  std::unique_ptr<char[]> p(new char[kBlock]);
  std::memset(p.get(), 1, kBlock);
  volatile char sink = p[kBlock - 1];
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

}  // namespace
}  // namespace sapmvs

#include "sapmvs/util/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "sapmvs/util/thread_count.h"

namespace sapmvs {
namespace {

TEST(ParallelFor, CallsEveryIndexOnceWhateverTheBlock) {
  for (const long n : {0L, 1L, 15L, 16L, 17L, 1000L, 100003L}) {
    for (const long block : {1L, 16L, 1000L}) {
      std::vector<std::atomic<int>> calls(n);
      for (auto& c : calls) c.store(0);
      ParallelFor(
          n, [&](long i) { calls[i].fetch_add(1); }, block);
      for (long i = 0; i < n; ++i) {
        ASSERT_EQ(calls[i].load(), 1) << "n " << n << " block " << block << " index " << i;
      }
    }
  }
}

// max_threads caps the calls running at once (tie-point SIFT holds a large
// pyramid per call), and 1 runs them all on the caller's thread.
TEST(ParallelFor, MaxThreadsCapsTheCallsAtOnce) {
  for (const int cap : {1, 2}) {
    std::atomic<int> running{0}, most{0};
    std::set<std::thread::id> ids;
    std::mutex m;
    ParallelFor(
        40,
        [&](long) {
          const int now = running.fetch_add(1) + 1;
          int seen = most.load();
          while (now > seen && !most.compare_exchange_weak(seen, now)) {
          }
          {
            std::lock_guard<std::mutex> lock(m);
            ids.insert(std::this_thread::get_id());
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
          running.fetch_sub(1);
        },
        1, cap);
    EXPECT_LE(most.load(), cap);
    EXPECT_LE(static_cast<int>(ids.size()), cap);
    if (cap == 1) {
      EXPECT_TRUE(ids.count(std::this_thread::get_id()));
    }
  }
}

TEST(ParallelFor, SharesTheWorkAndLeavesNoThreadBehind) {
  if (HostThreadCount() < 2) GTEST_SKIP() << "one host thread: nothing to share";
  std::mutex m;
  std::set<std::thread::id> ids;
  // Each call waits until a second thread has joined in (or gives up), so the
  // test does not depend on how quickly the extra thread starts.
  std::atomic<int> busy{0};
  ParallelFor(
      64,
      [&](long) {
        {
          std::lock_guard<std::mutex> lock(m);
          ids.insert(std::this_thread::get_id());
        }
        busy.fetch_add(1);
        for (int spin = 0; spin < 20000 && ids.size() < 2; ++spin) std::this_thread::yield();
      },
      1);
  EXPECT_EQ(busy.load(), 64);
  EXPECT_GE(ids.size(), 2u);
  EXPECT_LE(ids.size(), static_cast<size_t>(HostThreadCount()));
  EXPECT_TRUE(ids.count(std::this_thread::get_id())) << "the caller takes part";
}

// --threads holds on threads the program starts itself, where OpenMP's own
// count (omp_set_num_threads, per thread) does not reach.
TEST(ParallelFor, KeepsToTheThreadCountOnOtherThreadsToo) {
  const int all = HostThreadCount();
  if (all < 2) GTEST_SKIP() << "one host thread: no count below it to set";
  SetThreadCount(1);
  int seen = 0;
  std::set<std::thread::id> ids;
  std::thread side([&] {
    seen = HostThreadCount();
    std::mutex m;
    ParallelFor(
        64,
        [&](long) {
          std::lock_guard<std::mutex> lock(m);
          ids.insert(std::this_thread::get_id());
        },
        1);
  });
  side.join();
  SetThreadCount(all);  // what the other tests of this process expect
  EXPECT_EQ(seen, 1);
  EXPECT_EQ(ids.size(), 1u);
}

TEST(ParallelFor, RethrowsTheFirstFailureAfterEveryThreadStopped) {
  std::atomic<long> calls{0};
  auto run = [&] {
    ParallelFor(
        100000,
        [&](long i) {
          calls.fetch_add(1);
          if (i == 500) throw std::runtime_error("index 500");
        },
        10);
  };
  EXPECT_THROW(run(), std::runtime_error);
  // The indices after the failure were skipped, not all run.
  EXPECT_LT(calls.load(), 100000);
}

}  // namespace
}  // namespace sapmvs

#pragma once
// What the process holds in memory, for the reports and the memory budget.

#include <functional>
#include <type_traits>
#include <vector>

namespace sapmvs {

// Peak resident set size of this process, bytes: since the last
// ResetPeakRss() where that worked, else since the start.
double PeakRssBytes();

// Peak resident set size of this process since its start, whatever the
// resets.
double ProcessPeakRssBytes();

// Resident set size now, bytes; 0 where the system does not say (no /proc).
double CurrentRssBytes();

// Starts a new peak for PeakRssBytes() at the current RSS, so that one
// group's peak is measured apart from the groups before it (Linux's
// /proc/self/clear_refs). False where the system cannot; PeakRssBytes() then
// stays the process's peak.
bool ResetPeakRss();

// Hands the heap's free pages back to the system (glibc's malloc_trim), so
// that what one group freed is not counted in the next group's RSS. A no-op
// where the C library has no such call.
void ReleaseFreeMemory();

// Hands back the whole pages in [begin, end), which must lie inside one
// allocation that holds nothing there any more; they read as zeros when
// written again. For a container shrunk in place, whose capacity keeps the
// pages of its largest size resident otherwise. A no-op outside Linux.
void ReleasePages(void* begin, void* end);

// ReleasePages on the capacity past a vector's size.
template <class T, class A>
void ReleaseUnusedCapacity(std::vector<T, A>& v) {
  static_assert(std::is_trivially_destructible_v<T>, "the released tail holds no objects");
  ReleasePages(v.data() + v.size(), v.data() + v.capacity());
}

// Serves every allocation of 2 MiB or more with its own mapping, which free()
// hands straight back to the system. glibc otherwise raises that threshold
// to the largest block freed so far (up to 32 MiB): the points and neighbour
// tables a group allocates and frees at each pass then come from the heap,
// whose freed middle stays resident, and `city`'s peak RSS was 302 MB
// against 275 MB with this. Lower thresholds gained little more (272 MB at
// 256 KiB) for many more page faults (OpenCV's image buffers, the kernels'
// batches). Call once, before any thread starts; a no-op where the C
// library has no such setting.
void ReturnLargeBlocksToSystem();

// While one lives, blocks freed stay in the heap for the next allocation of
// their size instead of going back to the system (ReturnLargeBlocksToSystem);
// its end hands the heap's free pages back (ReleaseFreeMemory) and restores
// the 2 MiB threshold. For work that allocates and frees the same large
// buffers over and over: SIFT's pyramid, built afresh for each image, spent
// a third of the tie points' time in the page faults of its new mappings.
// Not for work whose peak matters more than its speed; not nested. mallopt
// is process-wide: the large blocks other threads free meanwhile are kept
// for reuse too, until the end.
class ScopedHeapReuse {
 public:
  ScopedHeapReuse();
  ~ScopedHeapReuse();
  ScopedHeapReuse(const ScopedHeapReuse&) = delete;
  ScopedHeapReuse& operator=(const ScopedHeapReuse&) = delete;
};

// Runs work() under a ScopedHeapReuse on another thread, and waits for it:
// work whose buffers are allocated and freed over and over (image pyramids,
// OpenCV's filters) then reuses them instead of paying each new mapping's
// page faults, and takes them from that thread's arena (and its helpers'),
// not from the main heap, where the holes they left under what this thread
// allocated next stayed resident (SIFT's pyramids lifted `small`'s peak in
// pmvs mode by 3 to 6 MiB). What the work freed last may stay in its arena
// (glibc trims a thread arena's top only when a block is freed there), for
// the threads that take that arena next. Rethrows what work() throws; runs
// it on this thread when no thread can be started.
void RunWithHeapReuse(const std::function<void()>& work);

// Whether address space reserved and never written costs nothing: true
// unless the process's address space or data is limited (RLIMIT_AS, as a
// batch system's h_vmem sets it; RLIMIT_DATA, ulimit -d) or the system
// commits every page it lends (vm.overcommit_memory = 2), where a
// reservation counts in full. False where the system does not say (no
// /proc).
bool UnwrittenMemoryIsFree();

}  // namespace sapmvs

#pragma once
// What the process holds in memory, for the reports and the memory budget.

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

}  // namespace sapmvs

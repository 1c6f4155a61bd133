#pragma once
// What the process holds in memory, for the reports and the memory budget.

namespace sapmvs {

// Peak resident set size of this process so far, bytes (getrusage).
double PeakRssBytes();

}  // namespace sapmvs

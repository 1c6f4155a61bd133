#include "sapmvs/memory_use.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace sapmvs {

double PeakRssBytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return 1024.0 * static_cast<double>(u.ru_maxrss);  // Linux reports kilobytes
}

double CurrentRssBytes() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

}  // namespace sapmvs

#include "sapmvs/util/memory_use.h"

#include <sys/resource.h>

namespace sapmvs {

double PeakRssBytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return 1024.0 * static_cast<double>(u.ru_maxrss);  // Linux reports kilobytes
}

}  // namespace sapmvs

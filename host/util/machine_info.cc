#include "util/machine_info.h"

#include <sched.h>
#include <unistd.h>

#include <fstream>
#include <thread>

namespace sapmvs {
namespace {

std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    // x86: "model name"; some ARM kernels give only "Processor" or "Hardware".
    if (line.rfind("model name", 0) != 0 && line.rfind("Processor", 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const size_t start = line.find_first_not_of(" \t", colon + 1);
    if (start != std::string::npos) return line.substr(start);
  }
  return "";
}

}  // namespace

MachineInfo DescribeMachine() {
  MachineInfo m;
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) == 0) m.hostname = host;
  m.cpu_model = CpuModel();
  // The CPUs this process may use (a container or taskset may allow fewer
  // than the machine has).
  cpu_set_t set;
  CPU_ZERO(&set);
  if (::sched_getaffinity(0, sizeof(set), &set) == 0) m.cores = CPU_COUNT(&set);
  if (m.cores <= 0) m.cores = static_cast<int>(std::thread::hardware_concurrency());
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGESIZE);
  if (pages > 0 && page_size > 0) {
    m.memory_bytes = static_cast<uint64_t>(pages) * static_cast<uint64_t>(page_size);
  }
  return m;
}

}  // namespace sapmvs

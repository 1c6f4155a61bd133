#pragma once
// The machine a run ran on, for its report: run times mean little without it.

#include <cstdint>
#include <string>

namespace sapmvs {

struct MachineInfo {
  std::string hostname;       // "" when unknown
  std::string cpu_model;      // /proc/cpuinfo's "model name"; "" when unknown
  int cores = 0;              // logical CPUs the process may run on
  uint64_t memory_bytes = 0;  // physical memory; 0 when unknown
};

MachineInfo DescribeMachine();

}  // namespace sapmvs

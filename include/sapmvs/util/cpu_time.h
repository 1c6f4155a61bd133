#pragma once
// The process's CPU time, to say how busy a stage kept the cores: its CPU
// seconds over its wall seconds (2 on two cores kept busy).

namespace sapmvs {

// User plus system CPU seconds of every thread of this process so far (the
// OpenCL CPU runtime's worker threads included); 0 where the system does not
// say.
double ProcessCpuSeconds();

}  // namespace sapmvs

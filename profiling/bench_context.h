#pragma once
// The OpenCL context shared by the benchmarks of one program: built once, with
// profiling on, on the default device (or SAPMVS_DEVICE). A benchmark that
// finds `error` set skips with it.

#include <benchmark/benchmark.h>

#include <exception>
#include <memory>
#include <string>

#include "device/cl_runtime.h"

namespace sapmvs::bench {

struct SharedContext {
  std::unique_ptr<ClContext> context;
  std::string error;
};

inline SharedContext& Shared() {
  static SharedContext* shared = [] {
    auto* s = new SharedContext;  // Leaked: see tests/cl_test_fixture.h.
    try {
      DeviceOptions options;
      options.profile = true;
      s->context = std::make_unique<ClContext>(options);
    } catch (const std::exception& e) {
      s->error = e.what();
    }
    return s;
  }();
  return *shared;
}

// The benchmarks' main(): records the device in the report's context.
inline int RunMain(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  const SharedContext& shared = Shared();
  benchmark::AddCustomContext("opencl_device", shared.context ? shared.context->device().Describe()
                                                              : "none (" + shared.error + ")");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace sapmvs::bench

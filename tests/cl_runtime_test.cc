#include "device/cl_runtime.h"

#include <gtest/gtest.h>

#include <cstdlib>

#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cl_test_fixture.h"
#include "device/cl_error.h"
#include "sapmvs/util/kernel_limits.h"

namespace sapmvs {
namespace {

using test::ScopedEnv;

class ClRuntimeTest : public test::ClTest {};

// Expects `statement` to throw `type` and binds its what() to `message`.
#define EXPECT_THROW_WHAT(statement, type, message)           \
  do {                                                        \
    try {                                                     \
      statement;                                              \
      ADD_FAILURE() << "expected " #type " from " #statement; \
    } catch (const type& e) {                                 \
      message = e.what();                                     \
    }                                                         \
  } while (0)

cl_int ReturnStatus(cl_int status) { return status; }

DeviceInfo FakeDevice(int index, std::string platform, std::string name, DeviceType type) {
  DeviceInfo device;
  device.index = index;
  device.platform_name = std::move(platform);
  device.platform_version = "OpenCL 1.2";
  device.name = std::move(name);
  device.vendor = "Vendor";
  device.type = type;
  device.available = true;
  return device;
}

// Three devices of different kinds, for selection rules without a driver.
std::vector<DeviceInfo> FakeDevices() {
  return {FakeDevice(0, "Intel(R) OpenCL", "Xeon", DeviceType::kCpu),
          FakeDevice(1, "Portable Computing Language", "pthread-x86", DeviceType::kCpu),
          FakeDevice(2, "NVIDIA CUDA", "NVIDIA H100", DeviceType::kGpu)};
}

// --- Errors -----------------------------------------------------------------

TEST(ClErrorTest, StatusNamesCoverOpenCl12) {
  EXPECT_EQ(ClStatusName(CL_SUCCESS), "CL_SUCCESS");
  EXPECT_EQ(ClStatusName(CL_INVALID_KERNEL_ARGS), "CL_INVALID_KERNEL_ARGS");
  EXPECT_EQ(ClStatusName(CL_INVALID_WORK_GROUP_SIZE), "CL_INVALID_WORK_GROUP_SIZE");
  EXPECT_EQ(ClStatusName(CL_INVALID_DEVICE_PARTITION_COUNT), "CL_INVALID_DEVICE_PARTITION_COUNT");
  EXPECT_EQ(ClStatusName(-1001), "CL_PLATFORM_NOT_FOUND_KHR");
  // Every OpenCL 1.2 code has its own name.
  std::set<std::string> names;
  for (cl_int status = 0; status >= -68; --status) {
    if (status < -19 && status > -30) continue;  // Unassigned range.
    const std::string name = ClStatusName(status);
    EXPECT_EQ(name.rfind("CL_", 0), 0u) << status;
    EXPECT_EQ(name.find("UNKNOWN"), std::string::npos) << status;
    names.insert(name);
  }
  EXPECT_EQ(names.size(), 20u + 39u);
  EXPECT_EQ(ClStatusName(-12345), "CL_UNKNOWN_STATUS(-12345)");
}

TEST(ClErrorTest, CheckMacroNamesStatusCallAndLocation) {
  std::string what;
  EXPECT_THROW_WHAT(CL_CHECK(ReturnStatus(CL_INVALID_KERNEL_ARGS)), ClError, what);
  EXPECT_NE(what.find("CL_INVALID_KERNEL_ARGS (-52)"), std::string::npos) << what;
  EXPECT_NE(what.find("ReturnStatus(CL_INVALID_KERNEL_ARGS)"), std::string::npos) << what;
  EXPECT_NE(what.find("cl_runtime_test.cc:"), std::string::npos) << what;
  try {
    CL_CHECK(ReturnStatus(CL_OUT_OF_RESOURCES));
  } catch (const Error& e) {  // Reaches main() as a sapmvs::Error.
    EXPECT_EQ(e.ExitCode(), 1);
    const auto* cl_error = dynamic_cast<const ClError*>(&e);
    ASSERT_NE(cl_error, nullptr);
    EXPECT_EQ(cl_error->status(), CL_OUT_OF_RESOURCES);
    EXPECT_EQ(cl_error->status_name(), "CL_OUT_OF_RESOURCES");
  }
  EXPECT_NO_THROW(CL_CHECK(ReturnStatus(CL_SUCCESS)));
}

// --- Device selection (no driver needed) --------------------------------------

TEST(ClDeviceSelectionTest, DefaultPrefersGpuThenPoclThenFirst) {
  ScopedEnv env("SAPMVS_DEVICE", std::nullopt);
  std::vector<DeviceInfo> devices = FakeDevices();
  EXPECT_EQ(SelectDeviceIndex(devices, {}), 2);
  devices.pop_back();
  EXPECT_EQ(SelectDeviceIndex(devices, {}), 1);
  devices.pop_back();
  EXPECT_EQ(SelectDeviceIndex(devices, {}), 0);
}

TEST(ClDeviceSelectionTest, IndexAndCaseInsensitiveSubstring) {
  ScopedEnv env("SAPMVS_DEVICE", std::nullopt);
  const std::vector<DeviceInfo> devices = FakeDevices();
  DeviceOptions options;
  options.device = "1";
  EXPECT_EQ(SelectDeviceIndex(devices, options), 1);
  options.device = " 0 ";
  EXPECT_EQ(SelectDeviceIndex(devices, options), 0);
  options.device = "portable";
  EXPECT_EQ(SelectDeviceIndex(devices, options), 1);
  options.device = "nViDiA";
  EXPECT_EQ(SelectDeviceIndex(devices, options), 2);
}

TEST(ClDeviceSelectionTest, FlagWinsOverEnvironment) {
  const std::vector<DeviceInfo> devices = FakeDevices();
  ScopedEnv env("SAPMVS_DEVICE", "xeon");
  EXPECT_EQ(SelectDeviceIndex(devices, {}), 0);
  EXPECT_EQ(EffectiveDeviceSpec({}).source, "SAPMVS_DEVICE");
  DeviceOptions options;
  options.device = "h100";
  EXPECT_EQ(SelectDeviceIndex(devices, options), 2);
  EXPECT_EQ(EffectiveDeviceSpec(options).source, "--device");
}

TEST(ClDeviceSelectionTest, UnmatchedSpecNamesSpecAndListsDevicesOnOneLine) {
  ScopedEnv env("SAPMVS_DEVICE", std::nullopt);
  const std::vector<DeviceInfo> devices = FakeDevices();
  DeviceOptions options;
  options.device = "radeon";
  std::string what;
  EXPECT_THROW_WHAT(SelectDeviceIndex(devices, options), NoDeviceError, what);
  EXPECT_NE(what.find("\"radeon\" (from --device)"), std::string::npos) << what;
  for (const DeviceInfo& device : devices) {
    EXPECT_NE(what.find(device.Describe()), std::string::npos) << what;
  }
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  EXPECT_EQ(NoDeviceError(what).ExitCode(), 2);

  for (const char* spec : {"3", "-1", "99999999999999999999999"}) {
    options.device = spec;
    EXPECT_THROW_WHAT(SelectDeviceIndex(devices, options), NoDeviceError, what);
    EXPECT_NE(what.find(std::string("index ") + spec), std::string::npos) << what;
    EXPECT_NE(what.find("out of range"), std::string::npos) << what;
    EXPECT_NE(what.find(devices[2].Describe()), std::string::npos) << what;
  }

  ScopedEnv bad_env("SAPMVS_DEVICE", "quantum");
  EXPECT_THROW_WHAT(SelectDeviceIndex(devices, {}), NoDeviceError, what);
  EXPECT_NE(what.find("\"quantum\" (from SAPMVS_DEVICE)"), std::string::npos) << what;
}

TEST(ClDeviceSelectionTest, OptionsCheck) {
  for (const char* good : {"", "0", "12", "pocl", "NVIDIA H100"}) {
    DeviceOptions options;
    options.device = good;
    EXPECT_TRUE(options.Check()) << good;
  }
  for (const char* bad : {"-1", "po\ncl"}) {
    DeviceOptions options;
    options.device = bad;
    EXPECT_FALSE(options.Check()) << bad;
  }
}

// --- Real devices ---------------------------------------------------------------

std::vector<DeviceInfo> ListDevicesOrSkip(bool* skip) {
  try {
    return ListDevices();
  } catch (const NoDeviceError&) {
    *skip = true;
    return {};
  }
}

TEST(ClDevicesTest, ListingFindsPoclCpuDevice) {
  bool skip = false;
  const std::vector<DeviceInfo> devices = ListDevicesOrSkip(&skip);
  if (skip) SAPMVS_SKIP_WITHOUT_OPENCL("no OpenCL platform installed");
  int pocl = -1;
  for (size_t i = 0; i < devices.size(); ++i) {
    const DeviceInfo& device = devices[i];
    EXPECT_EQ(device.index, static_cast<int>(i));
    EXPECT_NE(device.id, nullptr);
    EXPECT_GT(device.global_mem_bytes, 0u);
    EXPECT_GT(device.max_alloc_bytes, 0u);
    EXPECT_GT(device.compute_units, 0);
    EXPECT_GE(device.max_work_group_size, 1u);
    EXPECT_FALSE(device.max_work_item_sizes.empty());
    EXPECT_EQ(device.version.rfind("OpenCL ", 0), 0u) << device.version;
    EXPECT_EQ(device.opencl_c_version.rfind("OpenCL C ", 0), 0u) << device.opencl_c_version;
    if (device.IsPoclCpu() && pocl < 0) pocl = device.index;
  }
  if (pocl < 0) GTEST_SKIP() << "no PoCL CPU device (install pocl-opencl-icd)";
  EXPECT_EQ(devices[pocl].type, DeviceType::kCpu);

  ScopedEnv env("SAPMVS_DEVICE", std::nullopt);
  DeviceOptions options;
  options.device = std::to_string(pocl);
  EXPECT_EQ(SelectDeviceIndex(devices, options), pocl);
  options.device = "pocl";
  EXPECT_EQ(SelectDeviceIndex(devices, options), pocl);
  ScopedEnv pocl_env("SAPMVS_DEVICE", "PoCL");
  EXPECT_EQ(SelectDeviceIndex(devices, {}), pocl);
}

TEST(ClBuildOptionsTest, RenderedSortedWithStandard) {
  const BuildOptions options{{"WORK_GROUP_SIZE", "64"}, {"MAX_VIEWS", "8"}};
  EXPECT_EQ(options.Render(), "-cl-std=CL1.2 -D MAX_VIEWS=8 -D WORK_GROUP_SIZE=64");
  // Floats are C float literals, whole numbers included ("15f" is not one).
  EXPECT_EQ(BuildOptions().Define("S", 15.0f).Render(), "-cl-std=CL1.2 -D S=15.0f");
  EXPECT_EQ(BuildOptions().Define("S", 0.0f).Render(), "-cl-std=CL1.2 -D S=0.0f");
  EXPECT_EQ(BuildOptions().Define("S", 0.25f).Render(), "-cl-std=CL1.2 -D S=0.25f");
  EXPECT_EQ(BuildOptions().Define("S", 1e-4f).Render(), "-cl-std=CL1.2 -D S=9.99999975e-05f");
  EXPECT_EQ(BuildOptions().Define("B", 2).Define("A", 1).Render(),
            BuildOptions().Define("A", 1).Define("B", 2).Render());
  EXPECT_THROW(BuildOptions().Define("1X", 1), std::invalid_argument);
  EXPECT_THROW(BuildOptions().Define("X", "a b"), std::invalid_argument);
  EXPECT_THROW(BuildOptions().Define("X", ""), std::invalid_argument);
}

TEST(ClBuildOptionsTest, FloatDefinesParseBackExactly) {
  for (float value : {1e-4f, 0.1f, 3.0f, 1.17549435e-38f, -2.5e7f}) {
    const std::string text = BuildOptions().Define("V", value).defines().at("V");
    ASSERT_EQ(text.back(), 'f') << text;  // a float literal, not a double
    EXPECT_EQ(std::strtof(text.substr(0, text.size() - 1).c_str(), nullptr), value) << text;
  }
}

// --- Context, programs, launches -------------------------------------------------

constexpr char kIotaSource[] = R"CL(
__kernel void iota(__global int* out, const int n, __global int* launched) {
  const int i = (int)get_global_id(0);
  atomic_inc(launched);
  if (i < n) out[i] = i * SCALE;
}
)CL";

TEST_F(ClRuntimeTest, ProgramCacheKeyedByOptions) {
  // A fresh context, so the count does not depend on which tests ran before.
  ClContext fresh(context().device(), /*profile=*/false);
  EXPECT_EQ(fresh.NumCachedPrograms(), 0u);
  const ClProgram& a = fresh.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "64"}});
  const ClProgram& b = fresh.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "64"}});
  const ClProgram& c = fresh.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "32"}});
  EXPECT_EQ(&a, &b);
  EXPECT_EQ(a.get(), b.get());
  EXPECT_NE(&a, &c);
  EXPECT_NE(a.get(), c.get());
  EXPECT_EQ(fresh.NumCachedPrograms(), 2u);
  EXPECT_EQ(c.options(), "-cl-std=CL1.2 -D WORK_GROUP_SIZE=32");
  EXPECT_EQ(a.name(), "bilinear_sample.cl");

  // Source programs share the cache and its keying.
  const ClProgram& d = fresh.ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "1"}});
  EXPECT_EQ(&fresh.ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "1"}}), &d);
  EXPECT_NE(&fresh.ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "2"}}), &d);
  EXPECT_EQ(fresh.NumCachedPrograms(), 4u);
  EXPECT_THROW(fresh.ProgramFromSource("iota_test", "__kernel void x() {}", {{"SCALE", "1"}}),
               std::logic_error);
}

TEST_F(ClRuntimeTest, ProgramsBuiltOnSeveralThreadsAreCachedOncePerKey) {
  // Each thread asks for the same keys in its own order, so threads miss the
  // same key at once and build it twice; one program per key stays, and every
  // thread gets that one. Half the keys are source programs, half kernel
  // files (whose source the cache loads itself).
  ClContext fresh(context().device(), /*profile=*/false);
  constexpr int kThreads = 6;
  constexpr int kKeys = 6;
  const auto program = [&fresh](int k) -> const ClProgram& {
    if (k % 2 == 0) {
      return fresh.ProgramFromSource("iota_test", kIotaSource, {{"SCALE", std::to_string(k + 1)}});
    }
    return fresh.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", std::to_string(8 << k)}});
  };
  std::vector<std::vector<const ClProgram*>> got(kThreads, std::vector<const ClProgram*>(kKeys));
  std::vector<std::string> errors(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      try {
        for (int j = 0; j < kKeys; ++j) {
          const int k = (t + j) % kKeys;
          got[t][k] = &program(k);
        }
      } catch (const std::exception& e) {
        errors[t] = e.what();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int t = 0; t < kThreads; ++t) ASSERT_EQ(errors[t], "") << "thread " << t;
  EXPECT_EQ(fresh.NumCachedPrograms(), static_cast<size_t>(kKeys));
  for (int k = 0; k < kKeys; ++k) {
    const ClProgram* kept = &program(k);
    EXPECT_EQ(kept->options(), k % 2 == 0
                                   ? "-cl-std=CL1.2 -D SCALE=" + std::to_string(k + 1)
                                   : "-cl-std=CL1.2 -D WORK_GROUP_SIZE=" + std::to_string(8 << k));
    for (int t = 0; t < kThreads; ++t) EXPECT_EQ(got[t][k], kept) << "thread " << t << " key " << k;
  }
}

TEST_F(ClRuntimeTest, BrokenKernelThrowsProgramBuildErrorWithLog) {
  const size_t before = context().NumCachedPrograms();
  const std::string source =
      "__kernel void broken(__global float* out) {\n  out[0] = undeclared_thing_42;\n}\n";
  try {
    context().ProgramFromSource("broken_test.cl", source, {{"FLAVOUR", "3"}});
    FAIL() << "expected ProgramBuildError";
  } catch (const ProgramBuildError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.status(), CL_BUILD_PROGRAM_FAILURE) << what;
    EXPECT_NE(e.build_log().find("undeclared_thing_42"), std::string::npos) << e.build_log();
    EXPECT_NE(what.find("undeclared_thing_42"), std::string::npos) << what;
    EXPECT_NE(what.find("broken_test.cl"), std::string::npos) << what;
    EXPECT_NE(what.find("-cl-std=CL1.2 -D FLAVOUR=3"), std::string::npos) << what;
  }
  // A failed build is not cached: fixing the source must not need a restart.
  EXPECT_EQ(context().NumCachedPrograms(), before);
}

TEST_F(ClRuntimeTest, DeviceBytesCountLiveBuffersAndTheirPeak) {
  const double live = DeviceBytesInUse();
  ResetPeakDeviceBytes();
  EXPECT_EQ(PeakDeviceBytes(), live);
  {
    ClBuffer a(context(), 1000);
    ClBuffer b(context(), 24);
    EXPECT_EQ(DeviceBytesInUse(), live + 1024);
    // A move carries the count; the moved-from buffer holds none.
    ClBuffer c = std::move(b);
    EXPECT_EQ(DeviceBytesInUse(), live + 1024);
    a = ClBuffer(context(), 10);
    EXPECT_EQ(DeviceBytesInUse(), live + 34);
  }
  EXPECT_EQ(DeviceBytesInUse(), live);
  EXPECT_EQ(PeakDeviceBytes(), live + 1024 + 10);  // a's new buffer before the old one went
  ResetPeakDeviceBytes();
  EXPECT_EQ(PeakDeviceBytes(), live);
}

TEST_F(ClRuntimeTest, EnqueueRoundsGlobalUpToWorkGroupMultiple) {
  ClKernel kernel =
      context().ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "3"}}).Kernel("iota");
  constexpr int kN = 100;
  ClBuffer out(context(), kN * sizeof(cl_int));
  ClBuffer launched(context(), sizeof(cl_int));
  launched.WriteVector(std::vector<cl_int>{0});
  kernel.SetArgs(out, cl_int{kN}, launched);
  ClEvent event = context().Enqueue(kernel, kN, 64);
  event.Wait();
  std::vector<cl_int> values(kN);
  out.ReadVector(&values);
  for (int i = 0; i < kN; ++i) ASSERT_EQ(values[i], 3 * i);
  std::vector<cl_int> count(1);
  launched.ReadVector(&count);
  EXPECT_EQ(count[0], 128);
  EXPECT_TRUE(event.profiling());
  EXPECT_GT(event.DeviceTimeNs(), 0u);
}

// Each lease has a queue of its own while the lanes last, then the main
// one; two threads launching one kernel through Launch get their own results.
TEST_F(ClRuntimeTest, QueueLeasesGiveEachThreadItsOwnQueue) {
  ClContext fresh(context().device(), /*profile=*/false);
  const cl_command_queue main = fresh.queue();
  ASSERT_EQ(ClContext::kLanes, 2);
  std::set<cl_command_queue> seen;
  {
    const ClContext::QueueLease first = fresh.LeaseQueue();
    seen.insert(fresh.queue());
    std::thread([&] {
      const ClContext::QueueLease second = fresh.LeaseQueue();
      seen.insert(fresh.queue());
      // All lanes leased: a third thread's lease falls back to the main queue.
      std::thread([&] {
        const ClContext::QueueLease third = fresh.LeaseQueue();
        EXPECT_EQ(fresh.queue(), main);
      }).join();
    }).join();
    // Another thread's lease does not move this one's.
    EXPECT_EQ(seen.count(fresh.queue()), 1u);
  }
  EXPECT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen.count(main), 0u);
  EXPECT_EQ(fresh.queue(), main);

  ClKernel kernel =
      fresh.ProgramFromSource("iota_lease_test", kIotaSource, {{"SCALE", "5"}}).Kernel("iota");
  auto launches = [&](int n, bool* right) {
    const ClContext::QueueLease lease = fresh.LeaseQueue();
    *right = true;
    for (int round = 0; round < 20; ++round) {
      ClBuffer out(fresh, n * sizeof(cl_int));
      ClBuffer launched(fresh, sizeof(cl_int));
      launched.WriteVector(std::vector<cl_int>{0});
      fresh.Launch(kernel, static_cast<size_t>(n), 1, out, cl_int{n}, launched);
      std::vector<cl_int> values(n);
      out.ReadVector(&values);
      for (int i = 0; i < n; ++i) *right = *right && values[i] == 5 * i;
    }
  };
  bool right_a = false, right_b = false;
  std::thread a(launches, 301, &right_a);
  launches(517, &right_b);
  a.join();
  EXPECT_TRUE(right_a);
  EXPECT_TRUE(right_b);
}

TEST_F(ClRuntimeTest, WorkGroupLargerThanDeviceMaxThrowsBeforeEnqueue) {
  ClKernel kernel =
      context().ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "1"}}).Kernel("iota");
  ClBuffer out(context(), 16 * sizeof(cl_int));
  ClBuffer launched(context(), sizeof(cl_int));
  kernel.SetArgs(out, cl_int{16}, launched);
  const size_t too_big = context().device().max_work_group_size * 2;
  try {
    context().Enqueue(kernel, too_big, too_big);
    FAIL() << "expected Error";
  } catch (const ClError& e) {
    FAIL() << "the driver rejected the launch; Enqueue should have: " << e.what();
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("CL_DEVICE_MAX_WORK_GROUP_SIZE"), std::string::npos) << what;
    EXPECT_NE(what.find(std::to_string(too_big)), std::string::npos) << what;
    EXPECT_NE(what.find("iota"), std::string::npos) << what;
  }
  EXPECT_THROW(context().Enqueue(kernel, NDRange(16, 16), 16), Error);  // Dimension mismatch.
  EXPECT_THROW(context().Enqueue(kernel, 0, 16), Error);
}

TEST_F(ClRuntimeTest, WorkGroupMustMatchReqdWorkGroupSize) {
  ClKernel kernel = context()
                        .Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "64"}})
                        .Kernel("bilinear_sample");
  std::string what;
  EXPECT_THROW_WHAT(context().Enqueue(kernel, 128, 32), Error, what);
  EXPECT_NE(what.find("reqd_work_group_size 64"), std::string::npos) << what;
}

TEST_F(ClRuntimeTest, KernelArgumentErrorsNameTheArgument) {
  ClKernel kernel =
      context().ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "1"}}).Kernel("iota");
  EXPECT_EQ(kernel.num_args(), 3u);
  ClBuffer out(context(), 4 * sizeof(cl_int));
  EXPECT_THROW(kernel.SetArgs(out, cl_int{4}), std::logic_error);
  std::string what;
  EXPECT_THROW_WHAT(kernel.SetArgs(out, cl_double2{}, out), ClError, what);
  EXPECT_NE(what.find("argument 1"), std::string::npos) << what;
  EXPECT_NE(what.find("iota"), std::string::npos) << what;
  EXPECT_THROW(context().Program("bilinear_sample.cl").Kernel("no_such_kernel"), ClError);
}

TEST_F(ClRuntimeTest, BufferRoundTripAndRangeChecks) {
  ClBuffer buffer(context(), 8 * sizeof(float));
  EXPECT_EQ(buffer.size(), 8 * sizeof(float));
  const std::vector<float> in = {1, 2, 3, 4, 5, 6, 7, 8};
  buffer.WriteVector(in);
  std::vector<float> out(4);
  buffer.ReadVector(&out, 4 * sizeof(float));
  EXPECT_EQ(out, (std::vector<float>{5, 6, 7, 8}));
  EXPECT_THROW(buffer.WriteVector(in, sizeof(float)), Error);
  EXPECT_THROW(ClBuffer(context(), 0), Error);
  EXPECT_THROW(ClBuffer(context(), context().device().max_alloc_bytes + 1), Error);
  ClBuffer moved = std::move(buffer);
  EXPECT_EQ(moved.size(), 8 * sizeof(float));
  EXPECT_EQ(buffer.get(), nullptr);  // NOLINT(bugprone-use-after-move)
}

TEST_F(ClRuntimeTest, EventTimingNeedsProfilingQueue) {
  ClContext plain(context().device(), /*profile=*/false);
  EXPECT_FALSE(plain.profiling());
  ClKernel kernel =
      plain.ProgramFromSource("iota_test", kIotaSource, {{"SCALE", "1"}}).Kernel("iota");
  ClBuffer out(plain, 4 * sizeof(cl_int));
  ClBuffer launched(plain, sizeof(cl_int));
  kernel.SetArgs(out, cl_int{4}, launched);
  ClEvent event = plain.Enqueue(kernel, 4, 4);
  std::string what;
  EXPECT_THROW_WHAT(event.DeviceTimeNs(), Error, what);
  EXPECT_NE(what.find("DeviceOptions::profile"), std::string::npos) << what;
}

// A context released with a command still queued must wait for it: PoCL
// compiles a kernel's work-group function when it first runs, and a driver
// thread still compiling while the process exits crashed it at exit.
TEST_F(ClRuntimeTest, ReleasedContextHasFinishedItsQueue) {
  ClEvent event;
  {
    ClContext scoped(context().device(), /*profile=*/false);
    // A local size no other test uses, so the launch compiles a work-group
    // function of its own.
    ClKernel kernel =
        scoped.ProgramFromSource("iota_release_test", kIotaSource, {{"SCALE", "3"}}).Kernel("iota");
    ClBuffer out(scoped, 48 * sizeof(cl_int));
    ClBuffer launched(scoped, sizeof(cl_int));
    kernel.SetArgs(out, cl_int{48}, launched);
    event = scoped.Enqueue(kernel, 48, 3);
  }
  cl_int status = CL_QUEUED;
  ASSERT_EQ(clGetEventInfo(event.get(), CL_EVENT_COMMAND_EXECUTION_STATUS, sizeof(status), &status,
                           nullptr),
            CL_SUCCESS);
  EXPECT_EQ(status, CL_COMPLETE);
}

}  // namespace
}  // namespace sapmvs

#pragma once
// Shared fixture for tests that need an OpenCL device. The device comes from
// SAPMVS_TEST_DEVICE, else SAPMVS_DEVICE, else the PoCL CPU device (the
// reference device, so results do not depend on which GPU a machine has), else
// the default device. Without any OpenCL device the tests skip with the reason
// (fail with SAPMVS_REQUIRE_OPENCL=1);
// a spec that matches nothing fails, since that is a misconfiguration.

#include <gtest/gtest.h>

#include <cstdlib>
#include <exception>
#include <memory>
#include <optional>
#include <string>

#include "device/cl_runtime.h"
#include "test_util.h"

namespace sapmvs::test {

// The device options the tests use (see the file comment).
inline DeviceOptions TestDeviceOptions(const std::vector<DeviceInfo>& devices) {
  DeviceOptions options;
  for (const char* name : {"SAPMVS_TEST_DEVICE", "SAPMVS_DEVICE"}) {
    if (const char* env = std::getenv(name); env && *env) {
      options.device = env;
      return options;
    }
  }
  for (const DeviceInfo& device : devices) {
    if (device.IsPoclCpu()) {
      options.device = std::to_string(device.index);
      return options;
    }
  }
  return options;  // Default device.
}

class ClReleaseEnvironment;

class ClTest : public ::testing::Test {
 protected:
  struct Shared {
    std::unique_ptr<ClContext> context;
    bool skip = false;
    std::string reason;
  };

  void SetUp() override {
    const Shared& shared = GetShared();
    if (shared.skip) SAPMVS_SKIP_WITHOUT_OPENCL(shared.reason);
    ASSERT_TRUE(shared.context) << shared.reason;
  }

  ClContext& context() { return *GetShared().context; }

  // One context per test process, so programs are built once per process.
  // Released by ClReleaseEnvironment when the tests are done, before static
  // destruction: released (or leaked) later, a command still in flight can
  // keep a driver thread compiling while the process tears down under it.
  static Shared& GetShared() {
    if (!shared_) shared_ = new Shared(CreateShared());
    return *shared_;
  }

  // Finishes the shared context's queue and releases it; the next GetShared()
  // would make a new one.
  static void ReleaseShared() {
    if (!shared_) return;
    delete shared_;  // ~ClContext waits for the queue first
    shared_ = nullptr;
  }

 private:
  friend class ClReleaseEnvironment;
  static inline Shared* shared_ = nullptr;

  static Shared CreateShared() {
    Shared shared;
    std::vector<DeviceInfo> devices;
    try {
      devices = ListDevices();
    } catch (const NoDeviceError& e) {
      shared.skip = true;
      shared.reason = std::string("no OpenCL device: ") + e.what();
      return shared;
    }
    try {
      const DeviceOptions options = TestDeviceOptions(devices);
      shared.context = std::make_unique<ClContext>(devices[SelectDeviceIndex(devices, options)],
                                                   /*profile=*/true);
    } catch (const std::exception& e) {
      shared.reason = std::string("cannot create the test OpenCL context: ") + e.what();
    }
    return shared;
  }
};

// Registered once per test binary, before main: its TearDown runs after the
// last test and before exit.
class ClReleaseEnvironment : public ::testing::Environment {
 public:
  void TearDown() override { ClTest::ReleaseShared(); }
};
inline ::testing::Environment* const kClReleaseEnvironment =
    ::testing::AddGlobalTestEnvironment(new ClReleaseEnvironment);

}  // namespace sapmvs::test

#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"
#include "device/cl_devices.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::RunCli;

TEST(CliDevices, ListsDevicesAndMarksTheDefault) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli("devices", "env -u SAPMVS_DEVICE");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("compute units"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("* = default device"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\n*"), std::string::npos) << r.out;
  for (const DeviceInfo& d : ListDevices())
    EXPECT_NE(r.out.find(d.name), std::string::npos) << d.name;
}

TEST(CliDevices, ChoosesByIndexFlagOrEnvironment) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto flag = RunCli("devices --device 0");
  ASSERT_EQ(flag.exit_code, 0) << flag.err;
  EXPECT_NE(flag.out.find("\n*  0 "), std::string::npos) << flag.out;
  EXPECT_NE(flag.out.find("chosen by --device \"0\""), std::string::npos) << flag.out;
  const auto env = RunCli("devices", "SAPMVS_DEVICE=0");
  ASSERT_EQ(env.exit_code, 0) << env.err;
  EXPECT_NE(env.out.find("chosen by SAPMVS_DEVICE \"0\""), std::string::npos) << env.out;
}

TEST(CliDevices, SaysWhereBuiltKernelsAreKept) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto set = RunCli("devices", "SAPMVS_PROGRAM_CACHE=/some/folder");
  ASSERT_EQ(set.exit_code, 0) << set.err;
  EXPECT_NE(set.out.find("built kernels: kept in /some/folder"), std::string::npos) << set.out;
  const auto home = RunCli("devices", "env -u SAPMVS_PROGRAM_CACHE -u XDG_CACHE_HOME HOME=/h");
  ASSERT_EQ(home.exit_code, 0) << home.err;
  EXPECT_NE(home.out.find("kept in /h/.cache/sapmvs/programs"), std::string::npos) << home.out;
  const auto off = RunCli("devices", "SAPMVS_PROGRAM_CACHE=off");
  ASSERT_EQ(off.exit_code, 0) << off.err;
  EXPECT_NE(off.out.find("built kernels: not kept"), std::string::npos) << off.out;
}

TEST(CliDevices, UnmatchedDeviceIsOneLineAndExitCode2) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const auto r = RunCli("devices --device no-such-device-anywhere");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("no-such-device-anywhere"), std::string::npos) << r.err;
}

TEST(CliDevices, NoPlatformSaysHowToInstallPoclAndExits2) {
  // An ICD loader with an empty vendor folder sees no platform at all.
  const std::filesystem::path empty = test::ScratchDir();
  const auto r = RunCli("devices", "OCL_ICD_VENDORS=" + empty.string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("no OpenCL platform found"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("pocl-opencl-icd"), std::string::npos) << r.err;
}

// The CPU reference needs no OpenCL platform: without one `devices` still
// says what --device reference (or SAPMVS_DEVICE=reference) picks.
TEST(CliDevices, ReferenceNeedsNoPlatform) {
  const std::filesystem::path empty = test::ScratchDir();
  for (const std::string& how :
       {std::string("devices --device reference"), std::string("devices")}) {
    const std::string env =
        "OCL_ICD_VENDORS=" + empty.string() + (how == "devices" ? " SAPMVS_DEVICE=Reference" : "");
    const auto r = RunCli(how, env);
    EXPECT_EQ(r.exit_code, 0) << how << ": " << r.err;
    EXPECT_NE(r.out.find("the CPU reference backend"), std::string::npos) << how << ": " << r.out;
  }
}

}  // namespace
}  // namespace sapmvs

#include "kernel_source.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "sapmvs/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

using test::ScopedEnv;

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

TEST(KernelSourceTest, EmbeddedSourcesEqualFilesOnDisk) {
  const std::filesystem::path dir = SAPMVS_KERNEL_SOURCE_DIR;
  std::vector<std::string> on_disk;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ".cl") on_disk.push_back(entry.path().filename().string());
  }
  std::sort(on_disk.begin(), on_disk.end());
  // A mismatch here means the build did not re-run the embedding step.
  EXPECT_EQ(EmbeddedKernelFiles(), on_disk);
  EXPECT_NE(std::find(on_disk.begin(), on_disk.end(), "bilinear_sample.cl"), on_disk.end());

  ScopedEnv env("SAPMVS_KERNEL_DIR", std::nullopt);
  for (const std::string& file : EmbeddedKernelFiles()) {
    const std::string disk = ReadFile(dir / file);
    ASSERT_FALSE(disk.empty()) << file;
    EXPECT_EQ(EmbeddedKernelSource(file), disk) << file;
    EXPECT_EQ(KernelSource(file), disk) << file;
  }
}

TEST(KernelSourceTest, KernelDirOverrideReadsFromDisk) {
  const std::filesystem::path dir = test::ScratchDir();
  WriteFile(dir / "bilinear_sample.cl", "// edited copy\n");
  WriteFile(dir / "new_kernel.cl", "__kernel void k() {}\n");
  {
    ScopedEnv env("SAPMVS_KERNEL_DIR", dir.string());
    EXPECT_EQ(KernelSource("bilinear_sample.cl"), "// edited copy\n");
    // Kernels under development need not be embedded yet.
    EXPECT_EQ(KernelSource("new_kernel.cl"), "__kernel void k() {}\n");
    try {
      KernelSource("missing.cl");
      FAIL() << "expected Error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find((dir / "missing.cl").string()), std::string::npos)
          << e.what();
    }
    // The embedded copy stays reachable.
    EXPECT_NE(EmbeddedKernelSource("bilinear_sample.cl"), "// edited copy\n");
  }
  ScopedEnv empty("SAPMVS_KERNEL_DIR", "");
  EXPECT_EQ(KernelSource("bilinear_sample.cl"), EmbeddedKernelSource("bilinear_sample.cl"));
}

TEST(KernelSourceTest, UnknownFileNamesItAndTheAvailableFiles) {
  ScopedEnv env("SAPMVS_KERNEL_DIR", std::nullopt);
  try {
    KernelSource("no_such_kernel.cl");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("\"no_such_kernel.cl\""), std::string::npos) << what;
    EXPECT_NE(what.find("bilinear_sample.cl"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace sapmvs

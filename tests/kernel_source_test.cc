#include "device/kernel_source.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "sapmvs/util/error.h"
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

// Kernels share primitives by #include, expanded by ProgramSource: nested
// files in order, between #line directives, and the including file resumes
// at its next line.
TEST(KernelSourceTest, ProgramSourceExpandsIncludes) {
  const std::filesystem::path dir = test::ScratchDir();
  WriteFile(dir / "top.cl", "// top\n#include \"mid.cl\"\nkernel void k() {}\n");
  WriteFile(dir / "mid.cl", "  #  include \"leaf.cl\"  \nfloat mid(void);\n");
  WriteFile(dir / "leaf.cl", "float leaf(void);\n");
  WriteFile(dir / "missing_include.cl", "// a\n#include \"nowhere.cl\"\n");
  WriteFile(dir / "cycle.cl", "#include \"cycle.cl\"\n");
  ScopedEnv env("SAPMVS_KERNEL_DIR", dir.string());
  EXPECT_EQ(ProgramSource("top.cl"),
            "// top\n"
            "#line 1 \"mid.cl\"\n"
            "#line 1 \"leaf.cl\"\n"
            "float leaf(void);\n"
            "#line 2 \"mid.cl\"\n"
            "float mid(void);\n"
            "#line 3 \"top.cl\"\n"
            "kernel void k() {}\n");
  // Without includes it is the file itself.
  EXPECT_EQ(ProgramSource("leaf.cl"), "float leaf(void);\n");
  try {
    ProgramSource("missing_include.cl");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("missing_include.cl:2"), std::string::npos) << what;
    EXPECT_NE(what.find("nowhere.cl"), std::string::npos) << what;
  }
  try {
    ProgramSource("cycle.cl");
    FAIL() << "expected Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("cycle.cl:1"), std::string::npos) << what;
    EXPECT_NE(what.find("deeper than"), std::string::npos) << what;
  }
}

// Each kernel file takes the shared primitives from their one file instead
// of a copy: no definition of its own, exactly one in the program built.
TEST(KernelSourceTest, ProgramsTakeTheSharedPrimitivesFromOneFile) {
  ScopedEnv env("SAPMVS_KERNEL_DIR", std::nullopt);
  const struct {
    const char* program;
    const char* shared;
    std::vector<std::string> definitions;
  } cases[] = {
      {"bilinear_sample.cl", "bilinear.cl", {"float bilinear_at("}},
      {"ncc_score.cl", "ncc.cl", {"float bilinear_at(", "float ncc_of(", "void ncc_weights("}},
      {"patch_refine.cl", "ncc.cl", {"float bilinear_at(", "float ncc_of(", "void ncc_weights("}},
      {"roofline_probe.cl", "ncc.cl", {"float ncc_of(", "void ncc_weights("}},
  };
  auto count = [](const std::string& text, const std::string& what) {
    int n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  for (const auto& c : cases) {
    const std::string own = EmbeddedKernelSource(c.program);
    const std::string program = ProgramSource(c.program);
    EXPECT_NE(program.find(ProgramSource(c.shared)), std::string::npos) << c.program;
    for (const std::string& d : c.definitions) {
      EXPECT_EQ(count(own, d), 0) << c.program << " defines " << d << " itself";
      EXPECT_EQ(count(program, d), 1) << c.program << ": " << d;
    }
  }
}

}  // namespace
}  // namespace sapmvs

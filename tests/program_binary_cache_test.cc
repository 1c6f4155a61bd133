#include "device/program_binary_cache.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "cli_test_util.h"
#include "device/cl_runtime.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::ScopedEnv;

std::vector<unsigned char> AsBinary(const std::string& text) {
  return std::vector<unsigned char>(text.begin(), text.end());
}

void WriteCacheFile(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

std::vector<fs::path> CacheFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::exists(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) files.push_back(entry.path());
  return files;
}

class ProgramBinaryCacheTest : public test::ScratchTest {};

TEST_F(ProgramBinaryCacheTest, LoadsOnlyTheWholeEntryOfItsKey) {
  const ProgramBinaryCache cache(dir_ / "made" / "here");
  const std::string key = "platform: p\nsource:\n__kernel void k() {}\n";
  const std::vector<unsigned char> binary =
      AsBinary(std::string("\x7f"
                           "ELF\0binary",
                           10));
  EXPECT_FALSE(cache.Load(key).has_value());  // no folder yet
  ASSERT_TRUE(cache.Store(key, binary));
  ASSERT_EQ(CacheFiles(cache.folder()).size(), 1u);  // no temporary file left
  EXPECT_EQ(CacheFiles(cache.folder())[0], cache.EntryPath(key));
  ASSERT_TRUE(cache.Load(key).has_value());
  EXPECT_EQ(*cache.Load(key), binary);
  EXPECT_FALSE(cache.Load(key + " ").has_value());

  const std::string whole = test::Slurp(cache.EntryPath(key));
  ASSERT_GT(whole.size(), binary.size() + key.size());
  const fs::path other = cache.EntryPath("another key");
  // The entry under another key's name (as if their hashes met): its key is
  // not that key.
  WriteCacheFile(other, whole);
  EXPECT_FALSE(cache.Load("another key").has_value());
  // Damaged: cut short, grown, one byte of the binary or of the header
  // changed, emptied.
  const auto load_after = [&](const std::string& bytes) {
    WriteCacheFile(cache.EntryPath(key), bytes);
    return cache.Load(key).has_value();
  };
  EXPECT_FALSE(load_after(whole.substr(0, whole.size() - 1)));
  EXPECT_FALSE(load_after(whole + "x"));
  std::string flipped = whole;
  flipped[flipped.size() - 3] ^= 0x20;
  EXPECT_FALSE(load_after(flipped));
  std::string header = whole;
  header[2] = 'X';
  EXPECT_FALSE(load_after(header));
  EXPECT_FALSE(load_after(""));
  // A header that announces more than the file holds is not believed.
  const size_t binary_line = whole.find("binary ");
  ASSERT_NE(binary_line, std::string::npos);
  std::string huge = whole;
  huge.replace(binary_line, 7, "binary 99999999999");
  EXPECT_FALSE(load_after(huge));
  EXPECT_TRUE(load_after(whole));  // and the checks pass the original
  // A new store replaces the entry.
  ASSERT_TRUE(cache.Store(key, AsBinary("other")));
  EXPECT_EQ(*cache.Load(key), AsBinary("other"));
}

TEST_F(ProgramBinaryCacheTest, StoreFailsQuietlyWhereNoFolderCanBeMade) {
  WriteCacheFile(dir_ / "file", "not a folder");
  const ProgramBinaryCache cache(dir_ / "file" / "programs");
  EXPECT_FALSE(cache.Store("key", AsBinary("binary")));
  EXPECT_FALSE(cache.Load("key").has_value());
  const ProgramBinaryCache off;
  EXPECT_FALSE(off.enabled());
  EXPECT_FALSE(off.Store("key", AsBinary("binary")));
  EXPECT_FALSE(off.Load("key").has_value());
  EXPECT_FALSE(ProgramBinaryCache(dir_).Store("key", {}));  // nothing to keep
  EXPECT_EQ(CacheFiles(dir_).size(), 1u);
}

TEST(ProgramCacheFolderTest, SettingThenEnvironmentThenUserCacheFolder) {
  const ScopedEnv env("SAPMVS_PROGRAM_CACHE", std::nullopt);
  const ScopedEnv xdg("XDG_CACHE_HOME", "/x/cache");
  const ScopedEnv home("HOME", "/home/u");
  EXPECT_EQ(ProgramCacheFolder("/given"), fs::path("/given"));
  EXPECT_EQ(ProgramCacheFolder("off"), fs::path());
  EXPECT_EQ(ProgramCacheFolder(""), fs::path("/x/cache/sapmvs/programs"));
  {
    const ScopedEnv set("SAPMVS_PROGRAM_CACHE", "/from/env");
    EXPECT_EQ(ProgramCacheFolder(""), fs::path("/from/env"));
    EXPECT_EQ(ProgramCacheFolder("/given"), fs::path("/given"));  // the setting wins
  }
  {
    const ScopedEnv set("SAPMVS_PROGRAM_CACHE", "off");
    EXPECT_EQ(ProgramCacheFolder(""), fs::path());
  }
  {
    // The XDG specification ignores a relative XDG_CACHE_HOME.
    const ScopedEnv relative("XDG_CACHE_HOME", "relative");
    EXPECT_EQ(ProgramCacheFolder(""), fs::path("/home/u/.cache/sapmvs/programs"));
    const ScopedEnv no_home("HOME", std::nullopt);
    EXPECT_EQ(ProgramCacheFolder(""), fs::path());
  }
}

TEST(ProgramCacheKeyTest, NamesEverythingTheBinaryDependsOn) {
  DeviceInfo device;
  device.platform_name = "Portable Computing Language";
  device.platform_version = "OpenCL 3.0 PoCL 3.1";
  device.name = "cpu";
  device.vendor = "v";
  device.version = "OpenCL 3.0";
  device.driver_version = "3.1";
  const std::string key = ProgramCacheKey(device, "-D A=1", "__kernel void k() {}");
  const auto changed = [&](DeviceInfo d, const std::string& options, const std::string& source) {
    return ProgramCacheKey(d, options, source) != key;
  };
  EXPECT_FALSE(changed(device, "-D A=1", "__kernel void k() {}"));
  EXPECT_TRUE(changed(device, "-D A=2", "__kernel void k() {}"));
  EXPECT_TRUE(changed(device, "-D A=1", "__kernel void k() { }"));
  for (std::string DeviceInfo::*field :
       {&DeviceInfo::platform_name, &DeviceInfo::platform_version, &DeviceInfo::name,
        &DeviceInfo::vendor, &DeviceInfo::version, &DeviceInfo::driver_version}) {
    DeviceInfo other = device;
    other.*field += "+";
    EXPECT_TRUE(changed(other, "-D A=1", "__kernel void k() {}"));
  }
}

constexpr char kScaleSource[] = R"CL(
__kernel void scale(__global int* out, const int n) {
  const int i = (int)get_global_id(0);
  if (i < n) out[i] = i * SCALE + OFFSET;
}
)CL";

class ProgramBinaryCacheClTest : public test::ClTest {
 protected:
  void SetUp() override {
    test::ClTest::SetUp();
    dir_ = test::ScratchDir();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // What the `scale` kernel of `program` writes for 37 items.
  std::vector<cl_int> Scaled(ClContext& context, const ClProgram& program) {
    ClKernel kernel = program.Kernel("scale");
    constexpr int kN = 37;
    ClBuffer out(context, kN * sizeof(cl_int));
    kernel.SetArgs(out, cl_int{kN});
    context.Enqueue(kernel, kN, 8).Wait();
    std::vector<cl_int> values(kN);
    out.ReadVector(&values);
    return values;
  }

  fs::path dir_;
};

TEST_F(ProgramBinaryCacheClTest, LaterContextsLoadTheStoredBinary) {
  const ProgramBinaryCache cache(dir_);
  const BuildOptions defines{{"SCALE", "3"}, {"OFFSET", "-7"}};
  std::vector<cl_int> expected(37);
  for (int i = 0; i < 37; ++i) expected[i] = 3 * i - 7;

  ClContext first(context().device(), /*profile=*/false, cache);
  const ClProgram& built = first.ProgramFromSource("scale_test", kScaleSource, defines);
  EXPECT_FALSE(built.from_binary());
  const std::string key = ProgramCacheKey(context().device(), defines.Render(), kScaleSource);
  ASSERT_TRUE(cache.Load(key).has_value()) << "no entry in " << dir_;
  EXPECT_EQ(Scaled(first, built), expected);

  ClContext second(context().device(), /*profile=*/false, cache);
  const ClProgram& loaded = second.ProgramFromSource("scale_test", kScaleSource, defines);
  EXPECT_TRUE(loaded.from_binary());
  EXPECT_EQ(loaded.options(), defines.Render());
  EXPECT_EQ(Scaled(second, loaded), expected);

  // Other options are another program; kernel files are cached alike.
  const BuildOptions other{{"SCALE", "3"}, {"OFFSET", "5"}};
  EXPECT_FALSE(second.ProgramFromSource("scale_test", kScaleSource, other).from_binary());
  EXPECT_FALSE(first.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "16"}}).from_binary());
  EXPECT_TRUE(second.Program("bilinear_sample.cl", {{"WORK_GROUP_SIZE", "16"}}).from_binary());
  EXPECT_EQ(CacheFiles(dir_).size(), 3u);

  // Without a cache nothing is loaded or stored.
  ClContext none(context().device(), /*profile=*/false);
  EXPECT_FALSE(none.ProgramFromSource("scale_test", kScaleSource, defines).from_binary());
  EXPECT_EQ(CacheFiles(dir_).size(), 3u);
}

TEST_F(ProgramBinaryCacheClTest, ABinaryTheDriverRefusesIsBuiltAgainAndReplaced) {
  const ProgramBinaryCache cache(dir_);
  const BuildOptions defines{{"SCALE", "2"}, {"OFFSET", "1"}};
  const std::string key = ProgramCacheKey(context().device(), defines.Render(), kScaleSource);
  // A whole entry of the right key whose bytes are no program.
  const std::vector<unsigned char> junk = AsBinary("not a program binary");
  ASSERT_TRUE(cache.Store(key, junk));

  ClContext fresh(context().device(), /*profile=*/false, cache);
  const ClProgram& program = fresh.ProgramFromSource("scale_test", kScaleSource, defines);
  EXPECT_FALSE(program.from_binary());
  const std::vector<cl_int> values = Scaled(fresh, program);
  for (int i = 0; i < 37; ++i) ASSERT_EQ(values[i], 2 * i + 1);
  ASSERT_TRUE(cache.Load(key).has_value());
  EXPECT_NE(*cache.Load(key), junk);

  ClContext later(context().device(), /*profile=*/false, cache);
  EXPECT_TRUE(later.ProgramFromSource("scale_test", kScaleSource, defines).from_binary());
}

TEST_F(ProgramBinaryCacheClTest, AnUnwritableFolderLeavesBuildsAsWithout) {
  WriteCacheFile(dir_ / "file", "not a folder");
  ClContext fresh(context().device(), /*profile=*/false, ProgramBinaryCache(dir_ / "file" / "x"));
  const ClProgram& program =
      fresh.ProgramFromSource("scale_test", kScaleSource, {{"SCALE", "1"}, {"OFFSET", "0"}});
  EXPECT_FALSE(program.from_binary());
  EXPECT_EQ(Scaled(fresh, program)[36], 36);
}

// A run keeps its kernels where SAPMVS_PROGRAM_CACHE says, the next run
// loads them instead of building them (the entries stay as written), and
// the kernels loaded match as the built ones did: the same cloud.
TEST_F(ProgramBinaryCacheTest, ARunKeepsItsKernelsAndTheNextLoadsThemForTheSameCloud) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const fs::path block = test::Simulated("tiny", 1) / "block.yaml";
  const fs::path cache = dir_ / "programs";
  const std::string env = "SAPMVS_PROGRAM_CACHE=" + cache.string();
  const auto first =
      test::RunCli("run " + block.string() + " --out " + (dir_ / "a").string() + " -q", env);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::vector<fs::path> kept = CacheFiles(cache);
  ASSERT_FALSE(kept.empty());
  std::vector<fs::file_time_type> written;
  for (const fs::path& f : kept) written.push_back(fs::last_write_time(f));

  const auto second =
      test::RunCli("run " + block.string() + " --out " + (dir_ / "b").string() + " -q", env);
  ASSERT_EQ(second.exit_code, 0) << second.err;
  ASSERT_EQ(CacheFiles(cache), kept);
  for (size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(fs::last_write_time(kept[i]), written[i]) << kept[i] << " was built again";
  }
  const std::string cloud = test::Slurp(dir_ / "a" / "cloud.ply");
  ASSERT_FALSE(cloud.empty());
  EXPECT_TRUE(cloud == test::Slurp(dir_ / "b" / "cloud.ply"))
      << "the loaded kernels' cloud differs";
}

}  // namespace
}  // namespace sapmvs

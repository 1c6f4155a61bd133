// The program cache with a device: the programs a context builds are kept,
// later contexts and runs load them and compute the same (the file format,
// the folder and the key: program_binary_cache_test.cc, a host test).
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cl_test_fixture.h"
#include "cli_test_util.h"
#include "device/cl_runtime.h"
#include "device/program_binary_cache.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

std::vector<unsigned char> ClCacheBytes(const std::string& text) {
  return std::vector<unsigned char>(text.begin(), text.end());
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
  EXPECT_EQ(test::FolderEntries(dir_).size(), 3u);

  // Without a cache nothing is loaded or stored.
  ClContext none(context().device(), /*profile=*/false);
  EXPECT_FALSE(none.ProgramFromSource("scale_test", kScaleSource, defines).from_binary());
  EXPECT_EQ(test::FolderEntries(dir_).size(), 3u);
}

TEST_F(ProgramBinaryCacheClTest, ABinaryTheDriverRefusesIsBuiltAgainAndReplaced) {
  const ProgramBinaryCache cache(dir_);
  const BuildOptions defines{{"SCALE", "2"}, {"OFFSET", "1"}};
  const std::string key = ProgramCacheKey(context().device(), defines.Render(), kScaleSource);
  // A whole entry of the right key whose bytes are no program.
  const std::vector<unsigned char> junk = ClCacheBytes("not a program binary");
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
  test::WriteFileBytes(dir_ / "file", "not a folder");
  ClContext fresh(context().device(), /*profile=*/false, ProgramBinaryCache(dir_ / "file" / "x"));
  const ClProgram& program =
      fresh.ProgramFromSource("scale_test", kScaleSource, {{"SCALE", "1"}, {"OFFSET", "0"}});
  EXPECT_FALSE(program.from_binary());
  EXPECT_EQ(Scaled(fresh, program)[36], 36);
}

class ProgramBinaryCacheRunTest : public test::ScratchTest {};

// A run keeps its kernels where SAPMVS_PROGRAM_CACHE says, the next run
// loads them instead of building them (the entries stay as written), and
// the kernels loaded match as the built ones did: the same cloud.
TEST_F(ProgramBinaryCacheRunTest, ARunKeepsItsKernelsAndTheNextLoadsThemForTheSameCloud) {
  SAPMVS_REQUIRE_OPENCL_DEVICE();
  const fs::path block = test::Simulated("tiny", 1) / "block.yaml";
  const fs::path cache = dir_ / "programs";
  const std::string env = "SAPMVS_PROGRAM_CACHE=" + cache.string();
  const auto first =
      test::RunCli("run " + block.string() + " --out " + (dir_ / "a").string() + " -q", env);
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::vector<fs::path> kept = test::FolderEntries(cache);
  ASSERT_FALSE(kept.empty());
  // A store writes a new file and renames it over the entry (AtomicFile),
  // so an entry built again is another inode; a load sets its time.
  const auto inode = [](const fs::path& f) {
    struct stat st {};
    return ::stat(f.c_str(), &st) == 0 ? st.st_ino : ino_t{0};
  };
  std::vector<ino_t> written;
  const auto before = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (const fs::path& f : kept) {
    written.push_back(inode(f));
    fs::last_write_time(f, before);
  }

  const auto second =
      test::RunCli("run " + block.string() + " --out " + (dir_ / "b").string() + " -q", env);
  ASSERT_EQ(second.exit_code, 0) << second.err;
  ASSERT_EQ(test::FolderEntries(cache), kept);
  for (size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(inode(kept[i]), written[i]) << kept[i] << " was built again";
    EXPECT_GT(fs::last_write_time(kept[i]), before) << kept[i] << " not marked used";
  }
  const std::string cloud = test::Slurp(dir_ / "a" / "cloud.ply");
  ASSERT_FALSE(cloud.empty());
  EXPECT_TRUE(cloud == test::Slurp(dir_ / "b" / "cloud.ply"))
      << "the loaded kernels' cloud differs";
}

}  // namespace
}  // namespace sapmvs

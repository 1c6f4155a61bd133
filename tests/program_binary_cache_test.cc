#include "device/program_binary_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::ScopedEnv;

std::vector<unsigned char> AsBinary(const std::string& text) {
  return std::vector<unsigned char>(text.begin(), text.end());
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
  ASSERT_EQ(test::FolderEntries(cache.folder()).size(), 1u);  // no temporary file left
  EXPECT_EQ(test::FolderEntries(cache.folder())[0], cache.EntryPath(key));
  ASSERT_TRUE(cache.Load(key).has_value());
  EXPECT_EQ(*cache.Load(key), binary);
  EXPECT_FALSE(cache.Load(key + " ").has_value());

  const std::string whole = test::Slurp(cache.EntryPath(key));
  ASSERT_GT(whole.size(), binary.size() + key.size());
  const fs::path other = cache.EntryPath("another key");
  // The entry under another key's name (as if their hashes met): its key is
  // not that key.
  test::WriteFileBytes(other, whole);
  EXPECT_FALSE(cache.Load("another key").has_value());
  // Damaged: cut short, grown, one byte of the binary or of the header
  // changed, emptied.
  const auto load_after = [&](const std::string& bytes) {
    test::WriteFileBytes(cache.EntryPath(key), bytes);
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
  test::WriteFileBytes(dir_ / "file", "not a folder");
  const ProgramBinaryCache cache(dir_ / "file" / "programs");
  EXPECT_FALSE(cache.Store("key", AsBinary("binary")));
  EXPECT_FALSE(cache.Load("key").has_value());
  const ProgramBinaryCache off;
  EXPECT_FALSE(off.enabled());
  EXPECT_FALSE(off.Store("key", AsBinary("binary")));
  EXPECT_FALSE(off.Load("key").has_value());
  EXPECT_FALSE(ProgramBinaryCache(dir_).Store("key", {}));  // nothing to keep
  EXPECT_EQ(test::FolderEntries(dir_).size(), 1u);
}

TEST_F(ProgramBinaryCacheTest, KeepsTheFolderUnderItsSizeDroppingTheLeastRecentlyUsed) {
  const fs::path folder = dir_ / "programs";
  const std::vector<unsigned char> binary(1000, 7);
  // Room for three entries of this size, not four.
  const ProgramBinaryCache probe(folder);
  ASSERT_TRUE(probe.Store("probe", binary));
  const uintmax_t entry = fs::file_size(probe.EntryPath("probe"));
  fs::remove(probe.EntryPath("probe"));
  const ProgramBinaryCache cache(folder, 3 * entry + entry / 2);
  // Files that are not entries, which a user may keep in the folder they
  // named, are never removed, whatever their size or age.
  test::WriteFileBytes(folder / "notes.txt", std::string(5000, 'n'));
  test::WriteFileBytes(folder / "0123456789ABCDEF.bin", std::string(5000, 'n'));
  test::WriteFileBytes(folder / "0123456789abcdef.bin.tmp", std::string(5000, 'n'));
  const auto now = fs::file_time_type::clock::now();
  // Keys a (oldest), b, c stored in turn with their times an hour apart.
  const std::vector<std::string> keys = {"a", "b", "c"};
  for (size_t i = 0; i < keys.size(); ++i) {
    ASSERT_TRUE(cache.Store(keys[i], binary));
    fs::last_write_time(cache.EntryPath(keys[i]), now - std::chrono::hours(3 - i));
  }
  for (const std::string& k : keys) EXPECT_TRUE(fs::exists(cache.EntryPath(k))) << k;
  // Using a makes b the least recently used: d's store removes b only.
  ASSERT_TRUE(cache.Load("a").has_value());
  EXPECT_GT(fs::last_write_time(cache.EntryPath("a")), now - std::chrono::minutes(1));
  ASSERT_TRUE(cache.Store("d", binary));
  EXPECT_TRUE(fs::exists(cache.EntryPath("a")));
  EXPECT_FALSE(fs::exists(cache.EntryPath("b")));
  EXPECT_TRUE(fs::exists(cache.EntryPath("c")));
  EXPECT_TRUE(fs::exists(cache.EntryPath("d")));
  EXPECT_EQ(test::FolderEntries(folder).size(), 6u);
  // An entry larger than the whole size is kept once stored (the run that
  // built it loads it next time), and the others make way for it.
  const ProgramBinaryCache small(folder, entry);
  ASSERT_TRUE(small.Store("e", std::vector<unsigned char>(3 * entry, 1)));
  EXPECT_TRUE(fs::exists(small.EntryPath("e")));
  for (const std::string k : {"a", "c", "d"}) EXPECT_FALSE(fs::exists(small.EntryPath(k))) << k;
  EXPECT_EQ(test::FolderEntries(folder).size(), 4u);
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

}  // namespace
}  // namespace sapmvs

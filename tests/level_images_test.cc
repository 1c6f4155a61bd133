#include "sapmvs/block/level_images.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "match/group_data.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// A block's images at the level, kept once and read back by every later
// group: the same pixels as decoding, never a copy of another file or of the
// file as it was before it changed, and a store that cannot keep anything
// still reads.
class LevelImageStoreTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    test::ScratchTest::SetUp();
    fs::copy(test::Simulated("tiny", 1), dir_ / "tiny", fs::copy_options::recursive);
    block_ = ReadBlock(dir_ / "tiny" / "block.yaml");
  }
  // What decoding gives at `level` (LoadMatchGroup's pixels before the store).
  cv::Mat Decoded(int i, int level) const {
    const Camera c = block_.images[i].camera.Pinhole().Scaled(std::ldexp(1.0, -level));
    return ResampleToLevel(LoadUndistorted(block_.images[i]).pixels, level, c.width(), c.height());
  }
  cv::Mat Read(const LevelImageStore& store, int i, int level, bool keep = true) const {
    const Camera c = block_.images[i].camera.Pinhole().Scaled(std::ldexp(1.0, -level));
    return store.Load(block_.images[i], level, c.width(), c.height(), keep);
  }
  static bool Same(const cv::Mat& a, const cv::Mat& b) {
    return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
  }
  static int Files(const fs::path& dir) {
    int n = 0;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) ++n;
    return n;
  }
  Block block_;
};

TEST_F(LevelImageStoreTest, KeepsEachImageOnceAndReadsTheSamePixelsBack) {
  const LevelImageStore store(dir_ / "levels");
  for (int level : {0, 1}) {
    for (int i = 0; i < 2; ++i) {
      const cv::Mat first = Read(store, i, level);
      ASSERT_TRUE(Same(first, Decoded(i, level))) << "image " << i << " level " << level;
    }
  }
  EXPECT_EQ(Files(dir_ / "levels"), 4);  // two images at two levels
  // Read back from the copy, not the file: the file's bytes spoilt, at the
  // same size and time, still read as the pixels kept.
  const cv::Mat kept = Decoded(0, 1);
  const fs::path file = block_.images[0].path;
  const auto time = fs::last_write_time(file);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(file) / 2));
    const std::string junk(64, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  fs::last_write_time(file, time);
  bool decodes_as_before = false;
  try {
    decodes_as_before = Same(Decoded(0, 1), kept);
  } catch (const std::exception&) {
  }
  ASSERT_FALSE(decodes_as_before) << "the spoilt file must not decode to the same pixels";
  EXPECT_TRUE(Same(Read(store, 0, 1), kept));
  store.Clear();
  EXPECT_FALSE(fs::exists(dir_ / "levels"));
}

TEST_F(LevelImageStoreTest, AChangedFileIsDecodedAgain) {
  const LevelImageStore store(dir_ / "levels");
  const cv::Mat before = Read(store, 0, 1);
  // Image 0's file now holds image 1's pixels, at another time.
  const fs::path file = block_.images[0].path;
  const auto time = fs::last_write_time(file);
  fs::copy_file(block_.images[1].path, file, fs::copy_options::overwrite_existing);
  fs::last_write_time(file, time + std::chrono::seconds(5));
  const cv::Mat after = Read(store, 0, 1);
  EXPECT_TRUE(Same(after, Decoded(0, 1)));
  EXPECT_FALSE(Same(after, before));
}

TEST_F(LevelImageStoreTest, ABrokenCopyIsDecodedAgain) {
  const LevelImageStore store(dir_ / "levels");
  Read(store, 0, 1);
  ASSERT_EQ(Files(dir_ / "levels"), 1);
  const fs::path copy = fs::directory_iterator(dir_ / "levels")->path();
  const std::uintmax_t whole = fs::file_size(copy);
  fs::resize_file(copy, whole / 2);
  EXPECT_TRUE(Same(Read(store, 0, 1), Decoded(0, 1)));
  EXPECT_EQ(fs::file_size(copy), whole);  // decoded, and kept whole again
  std::ofstream(copy, std::ios::binary | std::ios::trunc) << "not an image";
  EXPECT_TRUE(Same(Read(store, 0, 1), Decoded(0, 1)));
}

TEST_F(LevelImageStoreTest, ReadsWithoutKeepingWhereItCannotOrIsToldNotTo) {
  // Its folder's place is taken by a file: nothing can be kept.
  std::ofstream(dir_ / "blocked") << "a file";
  const LevelImageStore blocked(dir_ / "blocked" / "levels");
  EXPECT_TRUE(Same(Read(blocked, 0, 1), Decoded(0, 1)));
  const LevelImageStore none;
  EXPECT_TRUE(Same(Read(none, 1, 1), Decoded(1, 1)));
  none.Clear();  // nothing to remove
  const LevelImageStore store(dir_ / "levels");
  EXPECT_TRUE(Same(Read(store, 0, 1, false), Decoded(0, 1)));
  EXPECT_FALSE(fs::exists(dir_ / "levels"));
  // A disk that would keep less free than asked: nothing kept.
  const LevelImageStore full(dir_ / "full", 1e30);
  EXPECT_TRUE(Same(Read(full, 0, 1), Decoded(0, 1)));
  EXPECT_EQ(Files(dir_ / "full"), 0);
  // With room, the same store keeps it.
  const LevelImageStore room(dir_ / "room", 0);
  Read(room, 0, 1);
  EXPECT_EQ(Files(dir_ / "room"), 1);
  // An image that cannot be read is named, as without the store.
  fs::remove(block_.images[1].path);
  try {
    Read(store, 1, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(block_.images[1].path.string()), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

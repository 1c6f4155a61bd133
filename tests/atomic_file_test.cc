#include "sapmvs/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "sapmvs/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test and process: other checkouts may run the same
// suite at the same time.
class AtomicFileTest : public test::ScratchTest {
 protected:
  int FileCount() const {
    return static_cast<int>(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
};

std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void Spit(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

TEST_F(AtomicFileTest, CommitRenamesTheTempFileOntoThePath) {
  const fs::path path = dir_ / "out.txt";
  AtomicFile file(path);
  EXPECT_EQ(file.path(), path);
  EXPECT_EQ(file.temp_path().parent_path(), dir_);
  EXPECT_EQ(file.temp_path().filename().string().rfind(".out.txt.tmp.", 0), 0u) << file.temp_path();
  Spit(file.temp_path(), "hello");
  EXPECT_FALSE(fs::exists(path));
  file.Commit();
  EXPECT_TRUE(file.committed());
  EXPECT_EQ(Slurp(path), "hello");
  EXPECT_FALSE(fs::exists(file.temp_path()));
  EXPECT_EQ(FileCount(), 1);
}

TEST_F(AtomicFileTest, ExceptionBeforeCommitLeavesNoFileAndNoTempFile) {
  const fs::path path = dir_ / "out.txt";
  EXPECT_THROW(WriteFileAtomically(path,
                                   [](const fs::path& tmp) {
                                     Spit(tmp, "partial");
                                     throw std::runtime_error("writer failed half-way");
                                   }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(FileCount(), 0);
}

TEST_F(AtomicFileTest, ExistingFileIsReplacedOnlyOnCommit) {
  const fs::path path = dir_ / "out.txt";
  Spit(path, "old");
  {
    AtomicFile abandoned(path);
    Spit(abandoned.temp_path(), "new but abandoned");
  }
  EXPECT_EQ(Slurp(path), "old");
  EXPECT_EQ(FileCount(), 1);

  AtomicFile file(path);
  Spit(file.temp_path(), "new");
  EXPECT_EQ(Slurp(path), "old");
  file.Commit();
  EXPECT_EQ(Slurp(path), "new");
  EXPECT_EQ(FileCount(), 1);
}

TEST_F(AtomicFileTest, WriteFileAtomicallyWritesThroughTheTempPath) {
  const fs::path path = dir_ / "data.bin";
  fs::path seen;
  WriteFileAtomically(path, [&](const fs::path& tmp) {
    seen = tmp;
    EXPECT_NE(tmp, path);
    Spit(tmp, "content");
  });
  EXPECT_EQ(Slurp(path), "content");
  EXPECT_FALSE(fs::exists(seen));
}

TEST_F(AtomicFileTest, TwoWritersOfOnePathGetDistinctTempFiles) {
  const fs::path path = dir_ / "out.txt";
  AtomicFile a(path), b(path);
  EXPECT_NE(a.temp_path(), b.temp_path());
}

TEST_F(AtomicFileTest, MissingDirectoryThrowsNamingThePath) {
  const fs::path path = dir_ / "no_such_dir" / "out.txt";
  try {
    AtomicFile file(path);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "no_such_dir"));
}

TEST_F(AtomicFileTest, CommitWithoutTempFileThrowsAndKeepsTheOldFile) {
  const fs::path path = dir_ / "out.txt";
  Spit(path, "old");
  AtomicFile file(path);
  EXPECT_THROW(file.Commit(), Error);
  EXPECT_FALSE(file.committed());
  EXPECT_EQ(Slurp(path), "old");
}

TEST_F(AtomicFileTest, DirectoryAsPathIsRefused) { EXPECT_THROW(AtomicFile file(dir_), Error); }

TEST_F(AtomicFileTest, WriteBytesAndTextReplaceTheFileWhole) {
  const fs::path path = dir_ / "image.bin";
  Spit(path, "old contents, longer than the new");
  const std::string bytes("a\0b\n", 4);  // binary-safe: keeps the NUL
  WriteBytesAtomically(path, bytes.data(), bytes.size());
  EXPECT_EQ(Slurp(path), bytes);
  WriteTextAtomically(path, "");
  EXPECT_EQ(fs::file_size(path), 0u);
  EXPECT_EQ(FileCount(), 1);  // no temp file left
  try {
    WriteTextAtomically(dir_ / "missing" / "x.txt", "x");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

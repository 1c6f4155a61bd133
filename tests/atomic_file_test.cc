#include "sapmvs/util/atomic_file.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "file_size_limit.h"
#include "sapmvs/util/error.h"
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

using test::Slurp;

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

// The writers' bug: the data sat in the stream's buffer, the check ran before
// the flush, and a full disk committed a 0-byte file. Here the whole text
// fits the buffer, so only the flush at the end can fail.
TEST_F(AtomicFileTest, FullDiskAtTheFinalFlushFailsNamingTheFileAndKeepsTheOldOne) {
  const fs::path path = dir_ / "report.json";
  Spit(path, "old");
  std::string what;
  {
    test::FileSizeLimit limit(100);
    if (!limit.ok()) GTEST_SKIP() << "cannot set RLIMIT_FSIZE";
    try {
      WriteStreamAtomically(path, [](std::ostream& out) {
        for (int i = 0; i < 100; ++i) out << "{\"line\": " << i << "}\n";
      });
    } catch (const Error& e) {
      what = e.what();
    }
  }
  EXPECT_EQ(what, path.string() + ": write failed: File too large");
  EXPECT_EQ(Slurp(path), "old");
  EXPECT_EQ(FileCount(), 1);  // no temporary file
}

TEST_F(AtomicFileTest, FullDiskInALargeWriteFailsNamingTheFile) {
  const fs::path path = dir_ / "cloud.ply";
  const std::string big(1 << 20, 'x');  // larger than the stream's buffer
  std::string what;
  {
    test::FileSizeLimit limit(4096);
    if (!limit.ok()) GTEST_SKIP() << "cannot set RLIMIT_FSIZE";
    try {
      WriteBytesAtomically(path, big.data(), big.size());
    } catch (const Error& e) {
      what = e.what();
    }
  }
  EXPECT_EQ(what, path.string() + ": write failed: File too large");
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(FileCount(), 0);
}

TEST_F(AtomicFileTest, TempNamesAreRecognisedWithTheirWritersPid) {
  long pid = 0;
  EXPECT_TRUE(IsAtomicTempName(".cloud.ply.tmp.1234.7", &pid));
  EXPECT_EQ(pid, 1234);
  EXPECT_TRUE(IsAtomicTempName(".dsm.tif.tmp.99.0.aux.xml", &pid));
  EXPECT_EQ(pid, 99);
  for (const char* name : {"cloud.ply.tmp.1.2", ".cloud.ply", ".x.tmp.1", ".x.tmp..2", ".x.tmp.a.2",
                           ".x.tmp.1.2b", ".tmp.1.2", "notes.txt"}) {
    EXPECT_FALSE(IsAtomicTempName(name)) << name;
  }
}

// A writer killed during a write leaves its hidden temporary file; the next
// command on the folder removes it, but not one a live process still writes,
// nor anything that is not an AtomicFile's.
TEST_F(AtomicFileTest, StaleTempFilesOfDeadWritersAreRemoved) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // now no such process
  const std::string dead = std::to_string(child), live = std::to_string(::getppid());
  const std::vector<std::string> stale = {".cloud.ply.tmp." + dead + ".3",
                                          ".dsm.tif.tmp." + dead + ".0.aux.xml"};
  const std::vector<std::string> kept = {".cloud.las.tmp." + live + ".1", "cloud.ply", ".hidden",
                                         "notes.tmp." + dead + ".1"};
  for (const auto& f : stale) Spit(dir_ / f, "partial");
  for (const auto& f : kept) Spit(dir_ / f, "keep");
  EXPECT_EQ(RemoveStaleTempFiles(dir_), 2);
  for (const auto& f : stale) EXPECT_FALSE(fs::exists(dir_ / f)) << f;
  for (const auto& f : kept) EXPECT_TRUE(fs::exists(dir_ / f)) << f;
}

}  // namespace
}  // namespace sapmvs

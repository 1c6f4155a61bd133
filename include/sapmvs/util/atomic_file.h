#pragma once
// Output files that appear whole or not at all. A run that fails or is killed
// half-way must not leave a truncated point cloud or raster that a later step
// (or the user) mistakes for a result, so writers fill a temporary file in the
// destination's directory and rename it onto the destination, which POSIX
// makes atomic within one file system.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <ostream>
#include <string>

namespace sapmvs {

class AtomicFile {
 public:
  // Throws sapmvs::Error naming `path` when its directory does not exist, so
  // a bad output path fails before any work is spent on the content.
  explicit AtomicFile(std::filesystem::path path);
  // Removes the temporary file unless Commit() succeeded.
  ~AtomicFile();

  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // The destination.
  const std::filesystem::path& path() const { return path_; }
  // Where to write: `.NAME.tmp.PID.N` beside the destination. Hidden, and
  // unique per process and object, so concurrent writers do not collide.
  const std::filesystem::path& temp_path() const { return temp_path_; }

  // Flushes the temporary file to the disk (fsync), renames it onto the
  // destination, replacing any file there, and syncs the directory: after a
  // crash the name holds the old file or the whole new one, never an empty
  // one. Throws sapmvs::Error naming the destination when the temporary file
  // is missing or a step fails; the destination is then untouched.
  void Commit();
  bool committed() const { return committed_; }

 private:
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  bool committed_ = false;
};

// Calls `write(tmp)` to fill a temporary file and commits it onto `path`. When
// `write` throws, the exception propagates and neither file is left behind.
void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& tmp)>& write);

// Calls `write(out)` to fill a temporary file through a stream that checks
// every write, then flushes, fsyncs, closes (checked) and commits it onto
// `path`. The first failed write, flush, fsync or close throws sapmvs::Error
// "PATH: write failed: REASON" (e.g. "No space left on device"), and neither
// a temporary file nor a changed `path` is left. A writer that stops early
// because the stream went bad needs no check of its own.
void WriteStreamAtomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream& out)>& write);

// Writes `size` bytes (an encoded image, a text) to `path` the same way.
void WriteBytesAtomically(const std::filesystem::path& path, const void* data, std::size_t size);
void WriteTextAtomically(const std::filesystem::path& path, const std::string& text);

// True for the name of a temporary file AtomicFile makes (`.NAME.tmp.PID.N`,
// or GDAL's `.aux.xml` side-car of one); sets `*pid` to the writer's pid.
bool IsAtomicTempName(const std::string& filename, long* pid = nullptr);

// Removes the temporary files in `dir` (not below it) left by writers that
// no longer run (killed during a write); returns how many. Those of a live
// process, which may still be writing, stay.
int RemoveStaleTempFiles(const std::filesystem::path& dir);

}  // namespace sapmvs

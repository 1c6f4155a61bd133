#include "sapmvs/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>
#include <utility>

#include "sapmvs/error.h"

namespace sapmvs {
namespace {

// Distinguishes two AtomicFiles for the same destination in one process
// (threads writing tiles); the pid alone only separates processes.
std::atomic<unsigned> temp_counter{0};

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  if (path_.empty() || !path_.has_filename()) {
    throw Error("'" + path_.string() +
                "': expected an output file path, got a directory or nothing");
  }
  const std::filesystem::path dir = path_.parent_path().empty() ? "." : path_.parent_path();
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw Error(path_.string() + ": cannot write, directory " + dir.string() + " does not exist");
  }
  if (std::filesystem::is_directory(path_, ec)) {
    throw Error(path_.string() + ": cannot write, it is a directory (expected a file path)");
  }
  temp_path_ = path_.parent_path() /
               ("." + path_.filename().string() + ".tmp." + std::to_string(::getpid()) + "." +
                std::to_string(temp_counter.fetch_add(1)));
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  std::error_code ec;  // a destructor must not throw; a leftover is harmless
  std::filesystem::remove(temp_path_, ec);
}

void AtomicFile::Commit() {
  if (committed_) return;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(temp_path_, ec)) {
    throw Error(path_.string() + ": cannot commit, the temporary file " + temp_path_.string() +
                " was not written");
  }
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) {
    throw Error(path_.string() + ": cannot replace with " + temp_path_.string() + " (" +
                ec.message() + ")");
  }
  committed_ = true;
}

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& tmp)>& write) {
  AtomicFile file(path);
  write(file.temp_path());
  file.Commit();
}

void WriteBytesAtomically(const std::filesystem::path& path, const void* data, std::size_t size) {
  WriteFileAtomically(path, [&](const std::filesystem::path& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(path.string() + ": cannot write (" + std::strerror(errno) + ")");
    const char* p = static_cast<const char*>(data);
    std::size_t left = size;
    int err = 0;
    while (left > 0 && err == 0) {
      const ssize_t n = ::write(fd, p, left);
      if (n > 0) {
        p += n;
        left -= static_cast<std::size_t>(n);
      } else if (n < 0 && errno != EINTR) {
        err = errno;
      } else if (n == 0) {
        err = EIO;
      }
    }
    if (err == 0 && ::fsync(fd) != 0) err = errno;
    if (::close(fd) != 0 && err == 0) err = errno;
    if (err != 0) throw Error(path.string() + ": write failed (" + std::strerror(err) + ")");
  });
}

void WriteTextAtomically(const std::filesystem::path& path, const std::string& text) {
  WriteBytesAtomically(path, text.data(), text.size());
}

}  // namespace sapmvs

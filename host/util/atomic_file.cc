#include "sapmvs/util/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <streambuf>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Distinguishes two AtomicFiles for the same destination in one process
// (threads writing tiles); the pid alone only separates processes.
std::atomic<unsigned> temp_counter{0};

std::string WriteFailed(const std::filesystem::path& path, int err) {
  return path.string() + ": write failed: " + std::strerror(err);
}

// Writes all of [data, data + size) to `fd`; 0 or the errno of the failure.
int WriteAll(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n > 0) {
      data += n;
      size -= static_cast<std::size_t>(n);
    } else if (n == 0) {
      return EIO;
    } else if (errno != EINTR) {
      return errno;
    }
  }
  return 0;
}

// A buffered output stream onto a file descriptor that keeps the errno of
// its first failed write: std::ofstream reports a full disk only as a bad
// stream (or not at all, when the failing flush is in its destructor).
class FdStreamBuf : public std::streambuf {
 public:
  explicit FdStreamBuf(int fd) : fd_(fd), buffer_(1 << 16) {
    setp(buffer_.data(), buffer_.data() + buffer_.size());
  }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (Drain() != 0) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n <= epptr() - pptr()) {
      traits_type::copy(pptr(), s, static_cast<std::size_t>(n));
      pbump(static_cast<int>(n));
      return n;
    }
    // Larger than the room left: drain, then write it straight through.
    if (Drain() != 0) return 0;
    if (error_ == 0) error_ = WriteAll(fd_, s, static_cast<std::size_t>(n));
    return error_ == 0 ? n : 0;
  }
  int sync() override { return Drain() == 0 ? 0 : -1; }

 private:
  int Drain() {
    if (error_ == 0 && pptr() > pbase()) {
      error_ = WriteAll(fd_, pbase(), static_cast<std::size_t>(pptr() - pbase()));
    }
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return error_;
  }

  int fd_;
  std::vector<char> buffer_;
  int error_ = 0;
};

// fsync of a file or directory by name; 0 or the errno of the failure.
int SyncPath(const std::filesystem::path& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) return errno;
  int err = ::fsync(fd) == 0 ? 0 : errno;
  // A directory or a read-only descriptor has nothing of ours to lose on close.
  ::close(fd);
  // Some file systems cannot sync a directory; the rename itself still holds.
  if (err == EINVAL || err == EROFS) err = 0;
  return err;
}

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
  // Writers that hand over a closed file (GDAL, encoders) have not synced it.
  if (const int err = SyncPath(temp_path_, O_RDONLY); err != 0) {
    throw Error(WriteFailed(path_, err));
  }
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) {
    throw Error(path_.string() + ": cannot replace with " + temp_path_.string() + " (" +
                ec.message() + ")");
  }
  committed_ = true;
  // The rename is durable once the directory is; a failure here leaves the
  // new file in place, so it is not reported.
  SyncPath(path_.parent_path().empty() ? "." : path_.parent_path(), O_RDONLY | O_DIRECTORY);
}

void WriteFileAtomically(const std::filesystem::path& path,
                         const std::function<void(const std::filesystem::path& tmp)>& write) {
  AtomicFile file(path);
  write(file.temp_path());
  file.Commit();
}

void WriteStreamAtomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream& out)>& write) {
  WriteFileAtomically(path, [&](const std::filesystem::path& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(path.string() + ": cannot write (" + std::strerror(errno) + ")");
    int err = 0;
    try {
      FdStreamBuf buf(fd);
      std::ostream out(&buf);
      write(out);
      out.flush();
      err = buf.error();
      if (err == 0 && !out) err = EIO;
    } catch (...) {
      ::close(fd);
      throw;
    }
    if (err == 0 && ::fsync(fd) != 0) err = errno;
    if (::close(fd) != 0 && err == 0) err = errno;
    if (err != 0) throw Error(WriteFailed(path, err));
  });
}

void WriteBytesAtomically(const std::filesystem::path& path, const void* data, std::size_t size) {
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  });
}

void WriteTextAtomically(const std::filesystem::path& path, const std::string& text) {
  WriteBytesAtomically(path, text.data(), text.size());
}

bool IsAtomicTempName(const std::string& filename, long* pid) {
  // .NAME.tmp.PID.N[.aux.xml]
  if (filename.size() < 2 || filename[0] != '.') return false;
  std::string name = filename;
  const std::string aux = ".aux.xml";
  if (name.size() > aux.size() && name.compare(name.size() - aux.size(), aux.size(), aux) == 0) {
    name.resize(name.size() - aux.size());
  }
  const std::size_t tmp = name.rfind(".tmp.");
  if (tmp == std::string::npos || tmp < 2) return false;
  const std::string tail = name.substr(tmp + 5);  // PID.N
  const std::size_t dot = tail.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == tail.size()) return false;
  const std::string digits = tail.substr(0, dot) + tail.substr(dot + 1);
  if (digits.find_first_not_of("0123456789") != std::string::npos || dot > 9) return false;
  if (pid) *pid = std::stol(tail.substr(0, dot));
  return true;
}

int RemoveStaleTempFiles(const std::filesystem::path& dir) {
  int removed = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    long pid = 0;
    if (!IsAtomicTempName(it->path().filename().string(), &pid)) continue;
    if (!it->is_regular_file(ec)) continue;
    // kill(pid, 0) fails with ESRCH only when no such process exists.
    if (pid > 0 && pid != ::getpid() && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      std::error_code rm;
      if (std::filesystem::remove(it->path(), rm)) ++removed;
    }
  }
  return removed;
}

}  // namespace sapmvs

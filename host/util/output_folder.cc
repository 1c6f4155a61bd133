#include "sapmvs/util/output_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace fs = std::filesystem;
namespace {

// The pid the lock holder wrote into the marker; "" when unreadable.
std::string HolderPid(int fd) {
  char buf[64] = {};
  const ssize_t n = ::pread(fd, buf, sizeof(buf) - 1, 0);
  if (n <= 0) return "";
  std::string text(buf, static_cast<size_t>(n));
  const size_t end = text.find_last_of("0123456789");
  if (end == std::string::npos) return "";
  const size_t begin = text.find_last_not_of("0123456789", end);
  return text.substr(begin == std::string::npos ? 0 : begin + 1,
                     end - (begin == std::string::npos ? 0 : begin + 1) + 1);
}

[[noreturn]] void ThrowBusy(const fs::path& dir, const std::string& command, int fd) {
  const std::string pid = HolderPid(fd);
  ::close(fd);
  throw Error(dir.string() + ": in use by another sapmvs " + command +
              (pid.empty() ? "" : " (pid " + pid + ")") +
              "; wait for it to finish or give another --out");
}

// Takes the lock on the open marker `fd`; false when another process holds
// it. File systems without flock (some network mounts) run unlocked rather
// than not at all.
bool Lock(int fd) {
  while (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    return errno != EWOULDBLOCK;
  }
  return true;
}

// What an earlier sapmvs left in a folder before markers existed.
bool HasLegacyOutput(const fs::path& dir, const std::string& command) {
  std::error_code ec;
  return command == "run" && fs::is_regular_file(dir / "groups" / "plan.json", ec);
}

}  // namespace

fs::path OutputFolder::MarkerPath(const fs::path& dir, const std::string& command) {
  return dir / (".sapmvs_" + command);
}

void OutputFolder::Check(const fs::path& dir, const std::string& command) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) return;
  if (!fs::is_directory(dir, ec)) {
    throw Error(dir.string() + ": exists and is not a folder; give a folder for --out");
  }
  const fs::path marker = MarkerPath(dir, command);
  if (fs::is_regular_file(marker, ec)) {
    const int fd = ::open(marker.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return;  // the constructor reports what it cannot open
    if (!Lock(fd)) ThrowBusy(dir, command, fd);
    ::close(fd);  // releases the probe's lock
    return;
  }
  if (HasLegacyOutput(dir, command) || fs::is_empty(dir, ec)) return;
  throw Error(dir.string() + ": folder is not empty and was not written by sapmvs " + command +
              " (no " + marker.filename().string() + "); give a new or empty folder");
}

OutputFolder::OutputFolder(fs::path dir, std::string command,
                           const std::vector<fs::path>& subfolders)
    : dir_(std::move(dir)), command_(std::move(command)) {
  Check(dir_, command_);
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) throw Error(dir_.string() + ": cannot create the output folder: " + ec.message());
  const fs::path marker = MarkerPath(dir_, command_);
  const int fd = ::open(marker.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw Error(marker.string() + ": cannot create (" + std::strerror(errno) + ")");
  // Another process may have come between Check() and here.
  if (!Lock(fd)) ThrowBusy(dir_, command_, fd);
  const std::string text = "sapmvs " + command_ + " pid " + std::to_string(::getpid()) + "\n";
  int err = 0;
  errno = 0;
  if (::ftruncate(fd, 0) != 0 ||
      ::pwrite(fd, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size()) ||
      ::fsync(fd) != 0) {
    err = errno != 0 ? errno : EIO;
  }
  if (err != 0) {
    ::close(fd);
    throw Error(marker.string() + ": write failed: " + std::strerror(err));
  }
  fd_ = fd;
  RemoveStaleTempFiles(dir_);
  for (const fs::path& sub : subfolders) RemoveStaleTempFiles(dir_ / sub);
}

OutputFolder::~OutputFolder() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock; the marker stays
}

}  // namespace sapmvs

#include "run/group_dispatch.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace fs = std::filesystem;

namespace {

bool IsClaimName(const std::string& name) {
  constexpr size_t kPrefix = 6;  // "group_"
  const std::string ext = ".claim";
  if (name.rfind("group_", 0) != 0 || name.size() <= kPrefix + ext.size()) return false;
  if (name.compare(name.size() - ext.size(), ext.size(), ext) != 0) return false;
  const std::string digits = name.substr(kPrefix, name.size() - kPrefix - ext.size());
  return digits.find_first_not_of("0123456789") == std::string::npos;
}

// Host and pid of rank 0 and the time: unique to this run among those that
// ever wrote the folder.
std::string MakeRunId() {
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) != 0) std::snprintf(host, sizeof(host), "unknown");
  const long long ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                           std::chrono::system_clock::now().time_since_epoch())
                           .count();
  return std::string(host) + "-" + std::to_string(::getpid()) + "-" + std::to_string(ms);
}

}  // namespace

fs::path ClaimPath(const fs::path& dir, int group) {
  char name[32];
  std::snprintf(name, sizeof(name), "group_%03d.claim", group + 1);
  return dir / name;
}

bool CreateClaim(const fs::path& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == EEXIST) return false;
    throw Error(path.string() + ": cannot create the group's claim (" + std::strerror(errno) + ")");
  }
  // The content only tells a later run whose claim it was; the file's
  // existence is the claim.
  const ssize_t n = ::write(fd, text.data(), text.size());
  ::close(fd);
  (void)n;
  return true;
}

void RemoveClaims(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (IsClaimName(it->path().filename().string())) {
      std::error_code rm;
      fs::remove(it->path(), rm);
    }
  }
}

void GroupDispatch::Start() {
  if (session_.size() == 1 || merges()) return;
  // Rank 0's Open(): "RUN_ID PROCESS_BYTES".
  std::istringstream text(session_.Broadcast(""));
  text >> run_id_ >> process_bytes_;
}

double GroupDispatch::PlanProcessBytes(double own) {
  if (session_.size() == 1 || merges()) process_bytes_ = own;
  return process_bytes_;
}

void GroupDispatch::Open(const fs::path& dir) {
  dir_ = dir;
  if (session_.size() == 1) return;
  if (merges()) {
    RemoveClaims(dir_);  // of earlier runs: rank 0 alone, before the others start
    run_id_ = MakeRunId();
    std::ostringstream text;
    text << run_id_ << " " << std::setprecision(17) << process_bytes_;
    session_.Broadcast(text.str());
  }
  // No group is matched until every rank has its block, plan and device: a
  // rank that cannot start stops the job before any work.
  session_.Barrier();
}

bool GroupDispatch::Claim(int group) {
  if (session_.size() > 1) {
    const std::string text = "run " + run_id_ + " rank " + std::to_string(session_.rank()) +
                             " pid " + std::to_string(::getpid()) + "\n";
    if (!CreateClaim(ClaimPath(dir_, group), text)) return false;
  }
  matched_.push_back(group);
  return true;
}

std::vector<int> GroupDispatch::Finish(int groups) {
  std::vector<int> by(static_cast<size_t>(groups), -1);
  for (const int g : matched_) by[static_cast<size_t>(g)] = session_.rank();
  if (session_.size() == 1) return by;
  by = session_.MaxOnRankZero(by);
  if (merges()) RemoveClaims(dir_);
  return by;
}

}  // namespace sapmvs

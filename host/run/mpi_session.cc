#include "run/mpi_session.h"

#include <sched.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <iostream>
#include <thread>

#include "sapmvs/util/error.h"
#include "sapmvs/util/log.h"

#ifdef SAPMVS_HAVE_MPI
#include <mpi.h>
#endif

namespace sapmvs {
namespace {

// The first of `names` set to a whole number, else -1.
int EnvInt(std::initializer_list<const char*> names) {
  for (const char* name : names) {
    const char* text = std::getenv(name);
    if (text == nullptr || *text == '\0') continue;
    char* end = nullptr;
    const long value = std::strtol(text, &end, 10);
    if (*end == '\0' && value >= 0 && value < (1L << 30)) return static_cast<int>(value);
  }
  return -1;
}

#ifdef SAPMVS_HAVE_MPI
// Waits for `request` with short sleeps instead of MPI's busy wait.
void WaitSleeping(MPI_Request* request) {
  for (int done = 0;;) {
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}
#endif

}  // namespace

LauncherEnvironment ReadLauncherEnvironment() {
  LauncherEnvironment env;
  const int ranks = EnvInt({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"});
  if (ranks <= 0) return env;
  env.ranks = ranks;
  env.rank = std::max(0, EnvInt({"OMPI_COMM_WORLD_RANK", "PMI_RANK"}));
  env.local_ranks = std::max(0, EnvInt({"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"}));
  return env;
}

int RankThreadCount() {
  const LauncherEnvironment env = ReadLauncherEnvironment();
  if (env.local_ranks <= 1) return 0;
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  cpu_set_t set;
  CPU_ZERO(&set);
  const int allowed = ::sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : 0;
  // A launcher that bound each rank to its own cores has divided them already.
  if (allowed > 0 && allowed < online) return allowed;
  return static_cast<int>(std::max(1L, online / env.local_ranks));
}

#ifdef SAPMVS_HAVE_MPI

MpiSession::MpiSession() {
  if (ReadLauncherEnvironment().ranks <= 0) return;
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) {
    // Only this (the main) thread calls MPI; OpenMP's threads never do.
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    joined_ = true;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
  MPI_Comm_rank(local, &local_rank_);
  MPI_Comm_size(local, &local_size_);
  MPI_Comm_free(&local);
}

MpiSession::~MpiSession() {
  if (!joined_) return;
  // Rank 0 may still be merging: the others wait here, asleep, rather than
  // in MPI_Finalize, which may spin.
  Barrier();
  MPI_Finalize();
}

void MpiSession::Barrier() {
  if (size_ == 1) return;
  MPI_Request request;
  MPI_Ibarrier(MPI_COMM_WORLD, &request);
  WaitSleeping(&request);
}

std::string MpiSession::Broadcast(const std::string& text) {
  if (size_ == 1) return text;
  int length = static_cast<int>(text.size());
  MPI_Request request;
  MPI_Ibcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD, &request);
  WaitSleeping(&request);
  std::string out = rank_ == 0 ? text : std::string(static_cast<size_t>(length), '\0');
  MPI_Ibcast(out.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD, &request);
  WaitSleeping(&request);
  return out;
}

std::vector<int> MpiSession::MaxOnRankZero(const std::vector<int>& values) {
  if (size_ == 1) return values;
  std::vector<int> out(values.size());
  MPI_Request request;
  MPI_Ireduce(values.data(), out.data(), static_cast<int>(values.size()), MPI_INT, MPI_MAX, 0,
              MPI_COMM_WORLD, &request);
  WaitSleeping(&request);
  return rank_ == 0 ? out : values;
}

void MpiSession::Abort(const std::string& message, int code) {
  std::cerr << "sapmvs: rank " << rank_ << " of " << size_ << ": " << message << std::endl;
  EndLog(code);
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

#else  // One process.

MpiSession::MpiSession() {
  const LauncherEnvironment env = ReadLauncherEnvironment();
  if (env.ranks > 1 && env.rank > 0) {
    // Rank 0 says it for the job. The pause lets its line out before
    // mpirun, seeing this exit, ends the others.
    std::this_thread::sleep_for(std::chrono::seconds(1));
    EndLog(1);
    std::exit(1);
  }
  if (env.ranks > 1) {
    throw Error(
        "this sapmvs was built without MPI; install openmpi-bin libopenmpi-dev and rebuild "
        "(scripts/install-deps.sh)");
  }
}

MpiSession::~MpiSession() = default;

std::string MpiSession::Broadcast(const std::string& text) { return text; }

void MpiSession::Barrier() {}

std::vector<int> MpiSession::MaxOnRankZero(const std::vector<int>& values) { return values; }

void MpiSession::Abort(const std::string& message, int code) {
  std::cerr << "sapmvs: " << message << std::endl;
  EndLog(code);
  std::exit(code);
}

#endif

}  // namespace sapmvs

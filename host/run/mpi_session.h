#pragma once
// The processes of one `sapmvs run` that an MPI launcher (mpirun) started:
// this file pair is the only code that calls MPI. Built without MPI
// (SAPMVS_HAVE_MPI undefined) the session is always one process, and a
// launch of several ranks is refused before any work, since N copies of a
// one-process run would all write the same folder.
//
// MPI is initialised only when a launcher started the process: a plain
// `sapmvs run` never loads it (OpenMPI's singleton start spawns a daemon,
// slow, and refused in some containers).
#include <string>
#include <vector>

namespace sapmvs {

// What the launcher says through the environment, read without MPI
// (OpenMPI's OMPI_COMM_WORLD_*, else MPICH's and Intel MPI's PMI_* and
// MPI_LOCAL*): 0 when the process was not started by a launcher.
struct LauncherEnvironment {
  int ranks = 0;        // in the whole job
  int rank = 0;         // of this process
  int local_ranks = 0;  // on this machine; 0 when the launcher does not say
};
LauncherEnvironment ReadLauncherEnvironment();

// The host threads (--threads 0) of one rank: when several ranks share this
// machine, its cores divided among them (at least 1), or the cores the
// launcher bound this process to when it bound it to fewer; 0 (all cores,
// the default) otherwise.
int RankThreadCount();

class MpiSession {
 public:
  // Joins the job when a launcher started this process; else a session of
  // one process. Throws Error when the launcher started several ranks and
  // this sapmvs was built without MPI.
  MpiSession();
  // Waits for every rank (without spinning), then leaves MPI.
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Rank among those on this machine, and how many there are.
  int local_rank() const { return local_rank_; }
  int local_size() const { return local_size_; }

  // Rank 0's `text`, on every rank. Waits by polling with short sleeps: MPI
  // busy-waits in blocking calls, which would take a core from the ranks
  // still matching.
  std::string Broadcast(const std::string& text);
  // Waits until every rank has called it; polls as Broadcast does.
  void Barrier();
  // For each i, the largest of the ranks' values[i], on rank 0 (other ranks
  // get their own values back). Polls as Broadcast does.
  std::vector<int> MaxOnRankZero(const std::vector<int>& values);

  // Prints "sapmvs: rank R of N: MESSAGE" and ends the whole job with `code`
  // (MPI_Abort): the other ranks would otherwise wait for this one forever.
  [[noreturn]] void Abort(const std::string& message, int code);

 private:
  bool joined_ = false;
  int rank_ = 0;
  int size_ = 1;
  int local_rank_ = 0;
  int local_size_ = 1;
};

}  // namespace sapmvs

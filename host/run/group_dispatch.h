#pragma once
// Which groups of a run this process matches, when mpirun started several
// (mpi_session.h): the ranks take the groups as they become free, each
// writes its groups' checkpoints into the shared DIR/groups, and rank 0,
// once every rank is done, merges. One process matches every group.
//
// A rank takes group g by creating DIR/groups/group_NNN.claim with
// O_CREAT|O_EXCL, holding the run's id (rank 0 makes it and broadcasts it).
// Claims in the shared folder rather than a dispatcher over MPI messages:
// rank 0 matches groups too without serving requests in between, it works
// wherever the ranks see one folder (exclusive create is atomic on local
// file systems and NFS), and no message has to say which groups are left.
// Claims that a killed run left (another run id) are removed by rank 0
// before the other ranks start, so no rank races another to take one over;
// a second run on the same folder is kept out by the folder's lock
// (output_folder.h). A rank that dies leaves its group unclaimed for the
// next run: without a done checkpoint the group is matched again.
#include <filesystem>
#include <string>
#include <vector>

#include "run/mpi_session.h"

namespace sapmvs {

// DIR/groups/group_NNN.claim of group `group` (0-based).
std::filesystem::path ClaimPath(const std::filesystem::path& dir, int group);
// Creates `path` holding `text` unless it exists (O_EXCL): true when this
// call made it. Throws Error when the folder cannot be written.
bool CreateClaim(const std::filesystem::path& path, const std::string& text);
// Removes every group_NNN.claim in `dir`.
void RemoveClaims(const std::filesystem::path& dir);

class GroupDispatch {
 public:
  explicit GroupDispatch(MpiSession& session) : session_(session) {}

  const MpiSession& session() const { return session_; }
  // The rank that makes the output folder and plan.json, draws the
  // progress, merges and writes the outputs: rank 0.
  bool merges() const { return session_.rank() == 0; }

  // Every rank calls Start() before its first look at the output folder,
  // and Open() once its device and checkpoints are set up
  // (run_checkpoint.h). The other ranks wait in Start() until rank 0 has
  // reached Open(), so that they find its folder, its lock and its
  // plan.json, and no claim of an earlier run; all wait in Open() until
  // every rank is ready.
  void Start();
  void Open(const std::filesystem::path& dir);

  // The process's memory the plan counts in every group's estimate
  // (PlanGroups' process_bytes): `own`, this process's, on rank 0 or alone;
  // rank 0's on the other ranks, so that every rank makes the same plan.
  double PlanProcessBytes(double own);

  // Whether this process matches `group`, not yet done: one process always;
  // a rank when it claims the group first.
  bool Claim(int group);

  // Waits until every rank has matched its groups; on rank 0, which rank
  // matched each of `groups` groups in this run (-1: none), and the claims
  // are removed. Other ranks get their own part.
  std::vector<int> Finish(int groups);

 private:
  MpiSession& session_;
  std::filesystem::path dir_;
  std::string run_id_;
  double process_bytes_ = 0;  // rank 0's, from Start() on the other ranks
  std::vector<int> matched_;  // groups this rank claimed
};

}  // namespace sapmvs

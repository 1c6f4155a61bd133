#pragma once
// The output folders of `sapmvs run` and `sapmvs simulate`. sapmvs writes
// into a folder only when it made it: a new or empty folder gets a marker
// file (`.sapmvs_run`, `.sapmvs_simulate`) before anything else, and a
// non-empty folder without one is refused, so that a user's own files are
// never overwritten. The marker is also the folder's lock (flock): a second
// command on a busy folder is refused naming the first one's pid, and the
// lock goes away with the process that held it, however it ended.

#include <filesystem>
#include <string>
#include <vector>

namespace sapmvs {

class OutputFolder {
 public:
  // Throws sapmvs::Error (one line naming `dir`) when `dir` cannot be the
  // output of `command` ("run" or "simulate"): it is not a folder, it holds
  // files but no marker of `command`, or another process holds its lock.
  // Writes nothing, so a failure found later at start-up leaves no trace.
  static void Check(const std::filesystem::path& dir, const std::string& command);

  // Check(), then creates `dir`, takes its lock (held until destruction),
  // writes the marker with this process's pid, and removes temporary files
  // that killed writers left in `dir` and in its `subfolders`.
  OutputFolder(std::filesystem::path dir, std::string command,
               const std::vector<std::filesystem::path>& subfolders = {});
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  // The marker (and lock) file of `command` in `dir`.
  static std::filesystem::path MarkerPath(const std::filesystem::path& dir,
                                          const std::string& command);

 private:
  std::filesystem::path dir_;
  std::string command_;
  int fd_ = -1;
};

}  // namespace sapmvs

#pragma once
// Built OpenCL programs kept on disk between runs, as the driver hands them
// out (CL_PROGRAM_BINARIES), so that a run loads its kernel variants instead
// of building them from source again. PoCL has a cache of its own, but finds
// an entry in it only after preprocessing the source, and with it clang's
// OpenCL header: 30 ms a program on a warm cache, against 2 ms to load the
// binary (a run builds eight; `small`'s matching waited for them).
//
// The cache can only save time: an entry that is missing, unreadable,
// another program's, truncated or altered is ignored (and replaced once the
// program is built from source), and a folder that cannot be made or
// written leaves the run as it would be without a cache.
//
// Every new build of sapmvs, device, driver and option set adds entries
// (about 2 MiB for a run's programs on PoCL), so the folder is kept under a
// size: a store removes the entries used least recently (a load marks its
// entry used) beyond it. Only files named as entries are ever removed.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "device/cl_devices.h"

namespace sapmvs {

// The folder that `setting` (DeviceOptions::program_cache) names: "off" =
// none (an empty path); "" = SAPMVS_PROGRAM_CACHE from the environment when
// set (which may also say "off"), else $XDG_CACHE_HOME/sapmvs/programs,
// else $HOME/.cache/sapmvs/programs, else none; anything else is the folder.
std::filesystem::path ProgramCacheFolder(const std::string& setting);

// Everything a program's binary depends on: the platform and its version,
// the device, its driver's version, the build options and the whole source.
// Entries are found by a hash of it and compared with it in full, so two
// programs never share one.
std::string ProgramCacheKey(const DeviceInfo& device, std::string_view options,
                            std::string_view source);

// The size a cache folder is kept under: some thirty sets of a run's
// programs on PoCL.
inline constexpr uintmax_t kProgramCacheBytes = uintmax_t{64} << 20;

class ProgramBinaryCache {
 public:
  ProgramBinaryCache() = default;  // disabled
  explicit ProgramBinaryCache(std::filesystem::path folder,
                              uintmax_t max_bytes = kProgramCacheBytes);

  bool enabled() const { return !folder_.empty(); }
  const std::filesystem::path& folder() const { return folder_; }
  // Where the entry of `key` lives (whether or not it exists).
  std::filesystem::path EntryPath(std::string_view key) const;

  // The binary stored for `key`; none without an entry, or when it cannot be
  // read or is not whole and `key`'s (its header's key, lengths and checksum).
  // A whole entry's time is set to now, where the folder lets it.
  std::optional<std::vector<unsigned char>> Load(std::string_view key) const;
  // Stores `binary` for `key` in place of any entry, whole or not at all
  // (AtomicFile), making the folder first, then removes the other entries
  // with the oldest times until the entries fit in max_bytes. False when the
  // store fails (a read-only or full disk), which leaves no file behind.
  bool Store(std::string_view key, const std::vector<unsigned char>& binary) const;

 private:
  void Prune(const std::filesystem::path& keep) const;

  std::filesystem::path folder_;
  uintmax_t max_bytes_ = kProgramCacheBytes;
};

}  // namespace sapmvs

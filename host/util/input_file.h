#pragma once
// Every file a user names is checked to be a regular file before it is
// opened: opening a FIFO for reading blocks until a writer appears, so a FIFO
// given as an input would hang the command forever.

#include <filesystem>
#include <fstream>
#include <string>

namespace sapmvs {

// Empty for a regular file; otherwise what the path is instead ("missing",
// "a folder", "a FIFO", ...). Does not open the path.
std::string NotRegularFile(const std::filesystem::path& path);

// Throws sapmvs::Error "PATH: cannot open file (...)" unless `path` is a
// regular file. For readers that hand the path to a library (GDAL, yaml-cpp).
void RequireRegularFile(const std::filesystem::path& path);

// Opens a regular file for reading; throws like RequireRegularFile, or when
// the open fails (permissions).
std::ifstream OpenInputFile(const std::filesystem::path& path,
                            std::ios::openmode mode = std::ios::in);

}  // namespace sapmvs

#pragma once
// World files (`.pgw` beside a PNG): where a north-up picture lies, for GIS
// that read plain images.
#include <filesystem>

namespace sapmvs {

// Writes, atomically, the world file of a north-up picture of square pixels
// of side `pixel` whose top-left corner (not its centre) is at (x, y).
void WriteWorldFile(const std::filesystem::path& path, double x, double y, double pixel);

}  // namespace sapmvs

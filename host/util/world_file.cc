#include "sapmvs/util/world_file.h"

#include <sstream>

#include "sapmvs/util/atomic_file.h"

namespace sapmvs {

void WriteWorldFile(const std::filesystem::path& path, double x, double y, double pixel) {
  // Pixel size, two rotations, the negative row size, then the centre of the
  // top-left pixel.
  std::ostringstream s;
  s.precision(17);
  s << pixel << "\n0\n0\n" << -pixel << "\n" << x + pixel / 2 << "\n" << y - pixel / 2 << "\n";
  WriteTextAtomically(path, s.str());
}

}  // namespace sapmvs

#include "util/input_file.h"

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace fs = std::filesystem;

std::string NotRegularFile(const fs::path& path) {
  std::error_code ec;
  // status() follows symbolic links, so a link to a FIFO is a FIFO.
  const fs::file_status s = fs::status(path, ec);
  switch (s.type()) {
    case fs::file_type::regular:
      return "";
    case fs::file_type::not_found:
      return "missing";
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::socket:
      return "a socket";
    case fs::file_type::block:
    case fs::file_type::character:
      return "a device";
    default:
      return ec ? ec.message() : "not a regular file";
  }
}

void RequireRegularFile(const fs::path& path) {
  const std::string problem = NotRegularFile(path);
  if (problem == "missing") throw Error(path.string() + ": cannot open file (missing)");
  if (!problem.empty()) {
    throw Error(path.string() + ": cannot open file (" + problem + ", expected a regular file)");
  }
}

std::ifstream OpenInputFile(const fs::path& path, std::ios::openmode mode) {
  RequireRegularFile(path);
  std::ifstream in(path, mode);
  if (!in) throw Error(path.string() + ": cannot open file (unreadable)");
  return in;
}

}  // namespace sapmvs

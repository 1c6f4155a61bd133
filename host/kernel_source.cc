#include "kernel_source.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "sapmvs/embedded_kernels.h"
#include "sapmvs/error.h"

namespace sapmvs {
namespace {

std::string AvailableFiles() {
  std::string list;
  for (const std::string& name : EmbeddedKernelFiles()) list += (list.empty() ? "" : ", ") + name;
  return list.empty() ? "(none)" : list;
}

}  // namespace

std::vector<std::string> EmbeddedKernelFiles() {
  std::vector<std::string> names;
  for (const embedded::KernelFile& file : embedded::kKernelFiles) names.emplace_back(file.name);
  return names;
}

std::string EmbeddedKernelSource(std::string_view file) {
  for (const embedded::KernelFile& entry : embedded::kKernelFiles) {
    if (entry.name != file) continue;
    std::string source;
    for (int i = 0; i < entry.num_chunks; ++i) source += entry.chunks[i];
    return source;
  }
  throw Error("unknown OpenCL kernel file \"" + std::string(file) +
              "\"; available: " + AvailableFiles());
}

std::string KernelSource(std::string_view file) {
  const char* dir = std::getenv("SAPMVS_KERNEL_DIR");
  if (dir == nullptr || *dir == '\0') return EmbeddedKernelSource(file);

  const std::filesystem::path path = std::filesystem::path(dir) / std::string(file);
  std::ifstream stream(path, std::ios::binary);
  if (!stream) {
    throw Error("cannot read OpenCL kernel file " + path.string() +
                " (SAPMVS_KERNEL_DIR is set); embedded files: " + AvailableFiles());
  }
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

}  // namespace sapmvs

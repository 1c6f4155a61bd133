#include "device/kernel_source.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "sapmvs/embedded_kernels.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr int kMaxIncludeDepth = 8;

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

namespace {

std::string ExpandIncludes(std::string_view file, int depth) {
  static const std::regex kInclude(R"re(^\s*#\s*include\s*"([^"]+)"\s*$)re");
  const std::string source = KernelSource(file);
  std::istringstream lines(source);
  std::string out;
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    std::smatch m;
    if (!std::regex_match(line, m, kInclude)) {
      out += line + "\n";
      continue;
    }
    const std::string where = std::string(file) + ":" + std::to_string(number);
    if (depth >= kMaxIncludeDepth) {
      throw Error(where + ": #include \"" + m[1].str() + "\" nested deeper than " +
                  std::to_string(kMaxIncludeDepth) + " files (an include cycle?)");
    }
    std::string included;
    try {
      included = ExpandIncludes(m[1].str(), depth + 1);
    } catch (const Error& e) {
      if (depth + 1 >= kMaxIncludeDepth) throw;
      throw Error(where + ": " + e.what());
    }
    out += "#line 1 \"" + m[1].str() + "\"\n" + included;
    out += "#line " + std::to_string(number + 1) + " \"" + std::string(file) + "\"\n";
  }
  return out;
}

}  // namespace

std::string ProgramSource(std::string_view file) { return ExpandIncludes(file, 0); }

}  // namespace sapmvs

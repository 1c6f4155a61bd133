#pragma once
// What the libFuzzer targets share: the readers take paths, so each input is
// written into a per-process work folder laid out as the reader expects.
// An input holds one or more files, separated by the line kSeparator (seeds
// are made the same way by scripts/fuzz.sh). sapmvs::Error is the readers'
// documented way to refuse an input; anything else escaping (another
// exception type, a crash, a sanitizer report, a leak) is a finding.

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "sapmvs/util/error.h"

namespace sapmvs::fuzz {

namespace fs = std::filesystem;

inline constexpr std::string_view kSeparator = "\n--8<--\n";
// The key of the program cache target's entries (its seeds are stored with
// it by make_seeds).
inline constexpr std::string_view kProgramCacheKey =
    "platform: fuzz\ndevice: fuzz\ndriver: 1\noptions: -D A=1\nsource:\n__kernel void k() {}\n";

// Up to `max_parts` pieces of the input; the last piece takes the rest.
inline std::vector<std::string> Split(const uint8_t* data, size_t size, size_t max_parts) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> parts;
  size_t start = 0;
  while (parts.size() + 1 < max_parts) {
    const size_t at = all.find(kSeparator, start);
    if (at == std::string_view::npos) break;
    parts.emplace_back(all.substr(start, at - start));
    start = at + kSeparator.size();
  }
  parts.emplace_back(all.substr(start));
  return parts;
}

inline void WriteFile(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
}

// A folder under $TMPDIR unique to this process, removed at exit.
inline const fs::path& WorkDir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("sapmvs-fuzz-" + std::to_string(getpid()));
    fs::remove_all(d);
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(fs::temp_directory_path() / ("sapmvs-fuzz-" + std::to_string(getpid())), ec);
    });
    return d;
  }();
  return dir;
}

// Stand-ins for the images the seeds name: the readers only look for the
// files (sizes are not checked), so they are empty. Names come from the file
// $SAPMVS_FUZZ_IMAGE_NAMES (one a line; scripts/fuzz.sh lists the shared
// data sets' images) plus a few generic ones.
inline void MakeImageStandIns(const fs::path& dir) {
  fs::create_directories(dir);
  std::vector<std::string> names = {"a.jpg", "b.jpg", "0000.jpg", "0001.jpg", "img.png"};
  if (const char* list = std::getenv("SAPMVS_FUZZ_IMAGE_NAMES")) {
    std::ifstream in(list);
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line.find('/') == std::string::npos) names.push_back(line);
    }
  }
  for (const std::string& n : names) WriteFile(dir / n, "");
}

// Runs `read`; sapmvs's own errors are accepted outcomes, anything else
// aborts so that libFuzzer records the input.
template <typename Fn>
void Run(Fn&& read) {
  try {
    read();
  } catch (const sapmvs::Error&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz: exception that is not sapmvs::Error: %s\n", e.what());
    std::abort();
  } catch (...) {
    std::fprintf(stderr, "fuzz: unknown exception\n");
    std::abort();
  }
}

}  // namespace sapmvs::fuzz

#include "device/program_binary_cache.h"

#include <algorithm>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <system_error>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr std::string_view kMagic = "sapmvs program binary 1\n";
// The magic line and the two length lines fit in this with room to spare.
constexpr uintmax_t kMaxHeaderBytes = 256;

// FNV-1a: stable across builds and machines, unlike std::hash, and enough
// to name an entry and to catch a damaged one (the key is compared whole).
uint64_t Fnv1a(const void* data, size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  uint64_t hash = 14695981039346656037ULL;
  for (size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ULL;
  return hash;
}

std::string Hex(uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016" PRIx64, value);
  return text;
}

// The line "NAME LENGTH CHECKSUM\n" at `*at` in `file`, which `*at` then
// passes; false unless it is one.
bool ReadField(const std::string& file, size_t* at, std::string_view name, size_t* length,
               std::string* checksum) {
  const size_t end = file.find('\n', *at);
  if (end == std::string::npos) return false;
  const std::string line = file.substr(*at, end - *at);
  *at = end + 1;
  if (line.compare(0, name.size(), name) != 0 || line.size() < name.size() + 1 ||
      line[name.size()] != ' ') {
    return false;
  }
  const std::string rest = line.substr(name.size() + 1);
  const size_t space = rest.find(' ');
  if (space == std::string::npos || space == 0) return false;
  char* parsed_end = nullptr;
  const unsigned long long value = std::strtoull(rest.c_str(), &parsed_end, 10);
  if (parsed_end != rest.c_str() + space) return false;
  *length = static_cast<size_t>(value);
  *checksum = rest.substr(space + 1);
  return true;
}

}  // namespace

std::filesystem::path ProgramCacheFolder(const std::string& setting) {
  std::string value = setting;
  if (value.empty()) {
    const char* env = std::getenv("SAPMVS_PROGRAM_CACHE");
    if (env != nullptr && *env != '\0') value = env;
  }
  if (value == "off") return {};
  if (!value.empty()) return value;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg == '/') {
    return std::filesystem::path(xdg) / "sapmvs" / "programs";
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home == '/') {
    return std::filesystem::path(home) / ".cache" / "sapmvs" / "programs";
  }
  return {};
}

std::string ProgramCacheKey(const DeviceInfo& device, std::string_view options,
                            std::string_view source) {
  std::string key;
  key += "platform: " + device.platform_name + " / " + device.platform_version + "\n";
  key += "device: " + device.name + " / " + device.vendor + " / " + device.version + "\n";
  key += "driver: " + device.driver_version + "\n";
  key += "options: " + std::string(options) + "\n";
  key += "source:\n" + std::string(source);
  return key;
}

ProgramBinaryCache::ProgramBinaryCache(std::filesystem::path folder, uintmax_t max_bytes)
    : folder_(std::move(folder)), max_bytes_(max_bytes) {}

std::filesystem::path ProgramBinaryCache::EntryPath(std::string_view key) const {
  return folder_ / (Hex(Fnv1a(key.data(), key.size())) + ".bin");
}

std::optional<std::vector<unsigned char>> ProgramBinaryCache::Load(std::string_view key) const {
  if (!enabled()) return std::nullopt;
  const std::filesystem::path path = EntryPath(key);
  std::error_code error;
  const uintmax_t size = std::filesystem::file_size(path, error);
  if (error) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  // The header alone first: a file whose size is not the one it announces
  // (cut short, grown, another file) is never read whole.
  std::string head(static_cast<size_t>(std::min<uintmax_t>(size, kMaxHeaderBytes)), '\0');
  if (!in.read(head.data(), static_cast<std::streamsize>(head.size()))) return std::nullopt;
  if (head.compare(0, kMagic.size(), kMagic) != 0) return std::nullopt;
  size_t at = kMagic.size();
  size_t key_length = 0;
  size_t binary_length = 0;
  std::string key_sum;
  std::string binary_sum;
  if (!ReadField(head, &at, "key", &key_length, &key_sum) ||
      !ReadField(head, &at, "binary", &binary_length, &binary_sum)) {
    return std::nullopt;
  }
  if (key_length != key.size() || binary_length == 0 || binary_length > size ||
      size != at + key_length + binary_length || key_sum != Hex(Fnv1a(key.data(), key.size()))) {
    return std::nullopt;
  }
  std::string body(key_length + binary_length, '\0');
  if (!in.seekg(static_cast<std::streamoff>(at)) ||
      !in.read(body.data(), static_cast<std::streamsize>(body.size())) ||
      body.compare(0, key_length, key) != 0) {
    return std::nullopt;
  }
  const char* binary = body.data() + key_length;
  if (binary_sum != Hex(Fnv1a(binary, binary_length))) return std::nullopt;
  std::filesystem::last_write_time(path, std::filesystem::file_time_type::clock::now(), error);
  return std::vector<unsigned char>(binary, binary + binary_length);
}

bool ProgramBinaryCache::Store(std::string_view key,
                               const std::vector<unsigned char>& binary) const {
  if (!enabled() || binary.empty()) return false;
  try {
    std::error_code error;
    std::filesystem::create_directories(folder_, error);
    if (error) return false;
    // What writers killed mid-entry left (AtomicFile's temporary names).
    RemoveStaleTempFiles(folder_);
    std::string header(kMagic);
    header += "key " + std::to_string(key.size()) + " " + Hex(Fnv1a(key.data(), key.size())) + "\n";
    header += "binary " + std::to_string(binary.size()) + " " +
              Hex(Fnv1a(binary.data(), binary.size())) + "\n";
    WriteStreamAtomically(EntryPath(key), [&](std::ostream& out) {
      out.write(header.data(), static_cast<std::streamsize>(header.size()));
      out.write(key.data(), static_cast<std::streamsize>(key.size()));
      out.write(reinterpret_cast<const char*>(binary.data()),
                static_cast<std::streamsize>(binary.size()));
    });
  } catch (const std::exception&) {  // Error from the write, filesystem_error
    return false;
  }
  Prune(EntryPath(key));
  return true;
}

void ProgramBinaryCache::Prune(const std::filesystem::path& keep) const {
  namespace fs = std::filesystem;
  struct Found {
    fs::file_time_type time;
    uintmax_t bytes;
    fs::path path;
  };
  std::vector<Found> entries;
  uintmax_t total = 0;
  std::error_code error;
  for (fs::directory_iterator it(folder_, error), end; !error && it != end; it.increment(error)) {
    const fs::path& path = it->path();
    const std::string name = path.filename().string();
    // Only our entries' names (EntryPath): 16 hexadecimal digits and ".bin".
    if (name.size() != 20 || name.compare(16, 4, ".bin") != 0 ||
        name.find_first_not_of("0123456789abcdef") != 16) {
      continue;
    }
    std::error_code e;
    if (!it->is_regular_file(e)) continue;
    // Either fails for an entry another run's prune removed meanwhile.
    Found f{it->last_write_time(e), 0, path};
    if (e) continue;
    f.bytes = it->file_size(e);
    if (e) continue;
    total += f.bytes;
    if (path != keep) entries.push_back(std::move(f));
  }
  if (error || total <= max_bytes_) return;
  std::sort(entries.begin(), entries.end(), [](const Found& a, const Found& b) {
    return a.time != b.time ? a.time < b.time : a.path < b.path;
  });
  for (const Found& f : entries) {
    if (total <= max_bytes_) break;
    // Another run may hold it open (it reads on) or have removed it.
    std::error_code e;
    fs::remove(f.path, e);
    total -= f.bytes;
  }
}

}  // namespace sapmvs

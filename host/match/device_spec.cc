#include "match/device_spec.h"

#include <cctype>
#include <cstdlib>
#include <string_view>
#include <vector>

#include "match/patch_kernels.h"

namespace sapmvs {
namespace {

std::string Trim(std::string_view text) {
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return std::string(text);
}

}  // namespace

DeviceSpec DeviceSpecFor(const std::string& device) {
  if (std::string spec = Trim(device); !spec.empty()) return {spec, "--device"};
  if (const char* env = std::getenv("SAPMVS_DEVICE")) {
    if (std::string spec = Trim(env); !spec.empty()) return {spec, "SAPMVS_DEVICE"};
  }
  return {};
}

std::string DeviceForLocalRank(const std::string& device, int local_rank) {
  const DeviceSpec spec = DeviceSpecFor(device);
  if (spec.value.find(',') == std::string::npos) return device;
  std::vector<std::string> entries;
  for (size_t begin = 0;;) {
    const size_t end = spec.value.find(',', begin);
    entries.push_back(Trim(std::string_view(spec.value).substr(begin, end - begin)));
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return entries[static_cast<size_t>(local_rank) % entries.size()];
}

bool IsReferenceSpec(const DeviceSpec& spec) {
  const std::string_view want = kReferenceDevice;
  if (spec.value.size() != want.size()) return false;
  for (size_t i = 0; i < want.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(spec.value[i])) != want[i]) return false;
  }
  return true;
}

}  // namespace sapmvs

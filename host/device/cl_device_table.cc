#include "device/cl_device_table.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "device/cl_devices.h"
#include "device/program_binary_cache.h"
#include "match/patch_kernels.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

std::string FormatGiB(uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f", static_cast<double>(bytes) / (1ull << 30));
  return text;
}

void PrintTable(const std::vector<std::vector<std::string>>& rows, std::ostream& out) {
  std::vector<size_t> widths;
  for (const auto& row : rows) {
    widths.resize(std::max(widths.size(), row.size()), 0);
    for (size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  }
  for (const auto& row : rows) {
    std::string line;
    for (size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(widths[c] - row[c].size() + 2, ' ');
    }
    out << line << "\n";
  }
}

}  // namespace

void PrintDeviceTable(const std::string& spec_text, std::ostream& out) {
  DeviceOptions options;
  options.device = spec_text;
  const DeviceSpec spec = EffectiveDeviceSpec(options);
  // The CPU reference needs no OpenCL device, so none found is no error here.
  const bool reference = IsReferenceSpec(spec);
  std::vector<DeviceInfo> devices;
  try {
    devices = ListDevices();
  } catch (const NoDeviceError&) {
    if (!reference) throw;
  }
  const int chosen = reference ? -1 : SelectDeviceIndex(devices, options);

  std::vector<std::vector<std::string>> rows = {{" ", "index", "platform", "device", "type",
                                                 "global mem (GiB)", "compute units", "image",
                                                 "OpenCL", "OpenCL C"}};
  for (const DeviceInfo& device : devices) {
    rows.push_back({device.index == chosen ? "*" : " ", std::to_string(device.index),
                    device.platform_name, device.name + (device.available ? "" : " (unavailable)"),
                    DeviceTypeName(device.type), FormatGiB(device.global_mem_bytes),
                    std::to_string(device.compute_units), device.image_support ? "yes" : "no",
                    ShortClVersion(device.version), ShortClVersion(device.opencl_c_version)});
  }
  if (!devices.empty()) PrintTable(rows, out);
  if (reference) {
    out << "chosen by " << spec.source << " \"" << spec.value
        << "\": the CPU reference backend (double precision, no OpenCL device)\n";
  } else if (spec.value.empty()) {
    out << "* = default device (first GPU, else the PoCL CPU device, else the first); "
           "choose another with --device INDEX|NAME|reference or SAPMVS_DEVICE\n";
  } else {
    out << "* = device chosen by " << spec.source << " \"" << spec.value << "\"\n";
  }
  if (reference) return;
  // Where a run keeps its built kernels, so that a user can find and clear it.
  const std::filesystem::path cache = ProgramCacheFolder(options.program_cache);
  if (cache.empty()) {
    out << "built kernels: not kept between runs (SAPMVS_PROGRAM_CACHE=off, or no cache folder)\n";
  } else {
    out << "built kernels: kept in " << cache.string() << " (SAPMVS_PROGRAM_CACHE names another, "
        << "or off)\n";
  }
}

}  // namespace sapmvs

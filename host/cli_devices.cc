// `sapmvs devices`: the OpenCL platforms and devices this machine offers and
// which one a run would use, so a user can pick `--device` before a long job.

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cl_runtime.h"
#include "cli.h"

namespace sapmvs::cli {
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

void RunDevices(const DeviceOptions& options, std::ostream& out) {
  const std::vector<DeviceInfo> devices = ListDevices();
  const int chosen = SelectDeviceIndex(devices, options);
  const DeviceSpec spec = EffectiveDeviceSpec(options);

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
  PrintTable(rows, out);
  if (spec.value.empty()) {
    out << "* = default device (first GPU, else the PoCL CPU device, else the first); "
           "choose another with --device INDEX|NAME or SAPMVS_DEVICE\n";
  } else {
    out << "* = device chosen by " << spec.source << " \"" << spec.value << "\"\n";
  }
}

}  // namespace

void RegisterDevicesCommand(CLI::App& app, const GlobalFlags& global) {
  // The table is the command's result, not progress, so --quiet keeps it.
  static_cast<void>(global);
  CLI::App* command = app.add_subcommand(
      "devices", "List OpenCL platforms and devices; * marks the one a run would use");
  // Shared so the options outlive this function; CLI11 keeps the callback.
  auto options = std::make_shared<DeviceOptions>();
  command->add_option("--device", options->device,
                      "Show which device this spec selects: an index from the table or a "
                      "case-insensitive part of the platform name/version, device name or "
                      "vendor (e.g. pocl, nvidia, cuda); default: $SAPMVS_DEVICE, else the "
                      "first GPU, else the PoCL CPU device");
  command->callback([options] { RunDevices(*options, std::cout); });
}

}  // namespace sapmvs::cli

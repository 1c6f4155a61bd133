// `sapmvs devices`: the OpenCL platforms and devices this machine offers and
// which one a run would use, so a user can pick `--device` before a long job.

#include <CLI/CLI.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "cli/cli.h"
#include "device/cl_device_table.h"

namespace sapmvs::cli {

void RegisterDevicesCommand(CLI::App& app, const GlobalFlags& global) {
  // The table is the command's result, not progress, so --quiet keeps it.
  static_cast<void>(global);
  CLI::App* command = app.add_subcommand(
      "devices", "List OpenCL platforms and devices; * marks the one a run would use");
  // Shared so the options outlive this function; CLI11 keeps the callback.
  auto device = std::make_shared<std::string>();
  command->add_option("--device", *device,
                      "Show which device this spec selects: an index from the table or a "
                      "case-insensitive part of the platform name/version, device name or "
                      "vendor (e.g. pocl, nvidia, cuda); default: $SAPMVS_DEVICE, else the "
                      "first GPU, else the PoCL CPU device; `reference` = the CPU reference "
                      "backend");
  command->callback([device] { PrintDeviceTable(*device, std::cout); });
}

}  // namespace sapmvs::cli

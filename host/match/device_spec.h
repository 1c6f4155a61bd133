#pragma once
// Which device a run asked for, before anything is asked of OpenCL: the
// --device flag, else SAPMVS_DEVICE. Kept apart from the OpenCL runtime so that
// choosing the CPU reference (patch_kernels.h) needs no OpenCL header.

#include <string>

namespace sapmvs {

// The device spec in effect and where it came from.
struct DeviceSpec {
  std::string value;   // Trimmed; "" = use the default.
  std::string source;  // "--device", "SAPMVS_DEVICE" or "" for the default.
};

// `device` (a --device value) trimmed, else SAPMVS_DEVICE trimmed, else none.
DeviceSpec DeviceSpecFor(const std::string& device);

// The entry of a comma list `device` (a --device value, else SAPMVS_DEVICE)
// that the rank `local_rank` of a machine takes: entry local_rank mod n, so
// that the ranks of one machine spread over its devices. A value without a
// comma is returned as it is.
std::string DeviceForLocalRank(const std::string& device, int local_rank);

// True when `spec` names the CPU reference backend (kReferenceDevice).
bool IsReferenceSpec(const DeviceSpec& spec);

}  // namespace sapmvs

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

// True when `spec` names the CPU reference backend (kReferenceDevice).
bool IsReferenceSpec(const DeviceSpec& spec);

}  // namespace sapmvs

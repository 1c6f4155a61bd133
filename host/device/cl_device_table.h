#pragma once
// The table `sapmvs devices` prints: the OpenCL platforms and devices this
// machine offers and which one a run would use (or that the spec picks the
// CPU reference), so a user can pick `--device` before a long job. On the
// device side of the wall, so the CLI needs no OpenCL header.

#include <ostream>
#include <string>

namespace sapmvs {

// `device`: a --device spec as DeviceOptions::device ("" = SAPMVS_DEVICE,
// else the default). Throws NoDeviceError when nothing matches or there is
// no OpenCL device (unless the spec picks the reference).
void PrintDeviceTable(const std::string& device, std::ostream& out);

}  // namespace sapmvs

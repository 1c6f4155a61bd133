#pragma once
// OpenCL device discovery and selection: every device of every platform,
// what `--device` (or SAPMVS_DEVICE) picks among them, and the default when
// nothing is asked for. ClContext (cl_runtime.h) opens the one chosen.

#include <CL/cl.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "match/device_spec.h"

namespace sapmvs {

enum class DeviceType { kGpu, kCpu, kOther };

// "GPU", "CPU" or "other".
const char* DeviceTypeName(DeviceType type);

struct DeviceInfo {
  int platform_index = -1;  // Position in clGetPlatformIDs' list.
  std::string platform_name;
  std::string platform_version;  // CL_PLATFORM_VERSION, e.g. "OpenCL 3.0 PoCL 3.1".
  int index = -1;                // Position in ListDevices(); what `--device N` means.
  std::string name;
  std::string vendor;
  DeviceType type = DeviceType::kOther;
  bool available = false;                   // CL_DEVICE_AVAILABLE and a compiler present.
  uint64_t global_mem_bytes = 0;            // CL_DEVICE_GLOBAL_MEM_SIZE.
  uint64_t max_alloc_bytes = 0;             // CL_DEVICE_MAX_MEM_ALLOC_SIZE: largest buffer.
  uint64_t local_mem_bytes = 0;             // CL_DEVICE_LOCAL_MEM_SIZE: per work-group.
  int compute_units = 0;                    // CL_DEVICE_MAX_COMPUTE_UNITS.
  size_t max_work_group_size = 0;           // CL_DEVICE_MAX_WORK_GROUP_SIZE, work-items.
  std::vector<size_t> max_work_item_sizes;  // Per dimension, work-items.
  bool image_support = false;
  // CL_DEVICE_HOST_UNIFIED_MEMORY: the device reads the host's memory as its
  // own (CPU devices, integrated GPUs), so a buffer can use host memory in
  // place rather than hold a copy of it.
  bool host_unified_memory = false;
  std::string version;           // CL_DEVICE_VERSION, e.g. "OpenCL 3.0 PoCL ...".
  std::string opencl_c_version;  // CL_DEVICE_OPENCL_C_VERSION, e.g. "OpenCL C 1.2 PoCL".
  std::string driver_version;    // CL_DRIVER_VERSION, e.g. "3.1+debian" or "550.54.15".
  cl_platform_id platform_id = nullptr;
  cl_device_id id = nullptr;

  // The PoCL CPU device, our reference device and CPU fallback.
  bool IsPoclCpu() const;
  // What a `--device` substring is matched against: platform name and version
  // (which is where "PoCL" and NVIDIA's "CUDA" appear), device name, vendor.
  std::string MatchText() const;
  // One-line description for messages: "0: Portable Computing Language / <name> (CPU)".
  std::string Describe() const;
};

// "3.0" from "OpenCL 3.0 PoCL ..." or "1.2" from "OpenCL C 1.2 ..."; the input
// unchanged when it does not have that form.
std::string ShortClVersion(const std::string& version);

// All devices of all platforms, platform by platform, in driver order. Throws
// NoDeviceError when there is no platform or no device at all.
std::vector<DeviceInfo> ListDevices();

struct DeviceOptions {
  // Which device to use. "" = SAPMVS_DEVICE from the environment if set, else
  // the default (first GPU, else the PoCL CPU device, else the first device).
  // Otherwise an index into ListDevices() or a case-insensitive substring of
  // DeviceInfo::MatchText(), i.e. platform name/version + device name + vendor
  // (first match wins), e.g. "pocl", "nvidia", "cuda".
  std::string device;
  // Create the queue with CL_QUEUE_PROFILING_ENABLE so ClEvent::DeviceTimeNs()
  // works. Costs a little per launch on some drivers.
  bool profile = false;
  // Where built programs are kept between runs (program_binary_cache.h):
  // "" = SAPMVS_PROGRAM_CACHE from the environment if set, else the user's
  // cache folder (~/.cache/sapmvs/programs); "off" = nowhere; else a folder.
  std::string program_cache;

  // False for a spec that can never match: a negative index or control
  // characters.
  bool Check() const;
};

// The device spec in effect and where it came from (device_spec.h).
DeviceSpec EffectiveDeviceSpec(const DeviceOptions& options);

// Index into `devices` of the default device (see DeviceOptions::device).
int DefaultDeviceIndex(const std::vector<DeviceInfo>& devices);

// Index into `devices` of the device `options` selects. Throws NoDeviceError
// naming the spec and listing the devices when nothing matches.
int SelectDeviceIndex(const std::vector<DeviceInfo>& devices, const DeviceOptions& options);

// An info string as a driver returns it, without its NUL terminator and the
// spaces some drivers pad it with.
std::string CleanInfoString(std::string text);

}  // namespace sapmvs

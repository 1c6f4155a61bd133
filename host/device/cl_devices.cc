#include "device/cl_devices.h"

#include <CL/cl_ext.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <iostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "device/cl_error.h"

namespace sapmvs {
namespace {

constexpr char kNoPlatformMessage[] =
    "no OpenCL platform found; install one, e.g. `sudo apt-get install pocl-opencl-icd` (CPU) "
    "or your GPU vendor's OpenCL driver";

std::string Trim(std::string_view text) {
  const auto is_space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!text.empty() && is_space(text.front())) text.remove_prefix(1);
  while (!text.empty() && is_space(text.back())) text.remove_suffix(1);
  return std::string(text);
}

std::string ToLower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string PlatformString(cl_platform_id platform, cl_platform_info param) {
  size_t size = 0;
  CL_CHECK(clGetPlatformInfo(platform, param, 0, nullptr, &size));
  std::string text(size, '\0');
  CL_CHECK(clGetPlatformInfo(platform, param, size, text.data(), nullptr));
  return CleanInfoString(std::move(text));
}

std::string DeviceString(cl_device_id device, cl_device_info param) {
  size_t size = 0;
  CL_CHECK(clGetDeviceInfo(device, param, 0, nullptr, &size));
  std::string text(size, '\0');
  CL_CHECK(clGetDeviceInfo(device, param, size, text.data(), nullptr));
  return CleanInfoString(std::move(text));
}

template <typename T>
T DeviceValue(cl_device_id device, cl_device_info param) {
  T value{};
  CL_CHECK(clGetDeviceInfo(device, param, sizeof(T), &value, nullptr));
  return value;
}

DeviceInfo QueryDevice(cl_platform_id platform, int platform_index, cl_device_id id) {
  DeviceInfo info;
  info.platform_index = platform_index;
  info.platform_name = PlatformString(platform, CL_PLATFORM_NAME);
  info.platform_version = PlatformString(platform, CL_PLATFORM_VERSION);
  info.platform_id = platform;
  info.id = id;
  info.name = DeviceString(id, CL_DEVICE_NAME);
  info.vendor = DeviceString(id, CL_DEVICE_VENDOR);
  const auto type = DeviceValue<cl_device_type>(id, CL_DEVICE_TYPE);
  info.type = (type & CL_DEVICE_TYPE_GPU)   ? DeviceType::kGpu
              : (type & CL_DEVICE_TYPE_CPU) ? DeviceType::kCpu
                                            : DeviceType::kOther;
  info.available = DeviceValue<cl_bool>(id, CL_DEVICE_AVAILABLE) &&
                   DeviceValue<cl_bool>(id, CL_DEVICE_COMPILER_AVAILABLE);
  info.global_mem_bytes = DeviceValue<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE);
  info.max_alloc_bytes = DeviceValue<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
  info.local_mem_bytes = DeviceValue<cl_ulong>(id, CL_DEVICE_LOCAL_MEM_SIZE);
  info.compute_units = static_cast<int>(DeviceValue<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS));
  info.max_work_group_size = DeviceValue<size_t>(id, CL_DEVICE_MAX_WORK_GROUP_SIZE);
  const auto dims = DeviceValue<cl_uint>(id, CL_DEVICE_MAX_WORK_ITEM_DIMENSIONS);
  info.max_work_item_sizes.resize(dims);
  CL_CHECK(clGetDeviceInfo(id, CL_DEVICE_MAX_WORK_ITEM_SIZES, dims * sizeof(size_t),
                           info.max_work_item_sizes.data(), nullptr));
  info.image_support = DeviceValue<cl_bool>(id, CL_DEVICE_IMAGE_SUPPORT) != CL_FALSE;
  info.host_unified_memory = DeviceValue<cl_bool>(id, CL_DEVICE_HOST_UNIFIED_MEMORY) != CL_FALSE;
  info.version = DeviceString(id, CL_DEVICE_VERSION);
  info.opencl_c_version = DeviceString(id, CL_DEVICE_OPENCL_C_VERSION);
  info.driver_version = DeviceString(id, CL_DRIVER_VERSION);
  return info;
}

std::string DeviceList(const std::vector<DeviceInfo>& devices) {
  std::string list;
  for (const DeviceInfo& device : devices) {
    if (!list.empty()) list += "; ";
    list += device.Describe();
  }
  return list;
}

bool IsIndexSpec(const std::string& spec) {
  const size_t digits = spec.size() > 1 && spec[0] == '-' ? 1 : 0;
  return spec.size() > digits && std::all_of(spec.begin() + digits, spec.end(), [](char c) {
           return std::isdigit(static_cast<unsigned char>(c)) != 0;
         });
}

}  // namespace

std::string CleanInfoString(std::string text) {
  text.resize(std::min(text.size(), text.find('\0')));
  return Trim(text);
}

const char* DeviceTypeName(DeviceType type) {
  switch (type) {
    case DeviceType::kGpu:
      return "GPU";
    case DeviceType::kCpu:
      return "CPU";
    case DeviceType::kOther:
      break;
  }
  return "other";
}

bool DeviceInfo::IsPoclCpu() const {
  return type == DeviceType::kCpu &&
         (platform_name == "Portable Computing Language" ||
          ToLower(platform_name + " " + platform_version).find("pocl") != std::string::npos);
}

std::string DeviceInfo::MatchText() const {
  return platform_name + " " + platform_version + " " + name + " " + vendor;
}

std::string DeviceInfo::Describe() const {
  return std::to_string(index) + ": " + platform_name + " / " + name + " (" + DeviceTypeName(type) +
         ")";
}

std::string ShortClVersion(const std::string& version) {
  for (const std::string prefix : {"OpenCL C ", "OpenCL "}) {
    if (version.rfind(prefix, 0) == 0) {
      const std::string rest = version.substr(prefix.size());
      return rest.substr(0, rest.find(' '));
    }
  }
  return version;
}

std::vector<DeviceInfo> ListDevices() {
  cl_uint num_platforms = 0;
  const cl_int status = clGetPlatformIDs(0, nullptr, &num_platforms);
  // The ICD loader reports "no vendor file installed" as CL_PLATFORM_NOT_FOUND_KHR.
  if (status == CL_PLATFORM_NOT_FOUND_KHR || (status == CL_SUCCESS && num_platforms == 0)) {
    throw NoDeviceError(kNoPlatformMessage);
  }
  if (status != CL_SUCCESS) {
    throw ClError(status, "clGetPlatformIDs(0, nullptr, &num_platforms)", __FILE__, __LINE__);
  }
  std::vector<cl_platform_id> platforms(num_platforms);
  CL_CHECK(clGetPlatformIDs(num_platforms, platforms.data(), nullptr));

  std::vector<DeviceInfo> devices;
  for (cl_uint p = 0; p < num_platforms; ++p) {
    // One broken driver (say, a GPU ICD without its kernel module) must not
    // hide the working ones, so a failing platform is skipped with a note.
    try {
      cl_uint num_devices = 0;
      const cl_int device_status =
          clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, 0, nullptr, &num_devices);
      if (device_status == CL_DEVICE_NOT_FOUND || num_devices == 0) continue;
      CL_CHECK(device_status);
      std::vector<cl_device_id> ids(num_devices);
      CL_CHECK(clGetDeviceIDs(platforms[p], CL_DEVICE_TYPE_ALL, num_devices, ids.data(), nullptr));
      for (cl_device_id id : ids) {
        devices.push_back(QueryDevice(platforms[p], static_cast<int>(p), id));
        devices.back().index = static_cast<int>(devices.size() - 1);
      }
    } catch (const ClError& e) {
      std::cerr << "sapmvs: warning: skipping OpenCL platform " << p << ": " << e.what() << "\n";
    }
  }
  if (devices.empty()) {
    throw NoDeviceError("no OpenCL device found on " + std::to_string(num_platforms) +
                        " OpenCL platform(s); install one, e.g. `sudo apt-get install "
                        "pocl-opencl-icd` (CPU) or your GPU vendor's OpenCL driver");
  }
  return devices;
}

bool DeviceOptions::Check() const {
  const std::string spec = Trim(device);
  if (IsIndexSpec(spec) && spec[0] == '-') return false;
  return std::none_of(spec.begin(), spec.end(),
                      [](char c) { return std::iscntrl(static_cast<unsigned char>(c)) != 0; });
}

DeviceSpec EffectiveDeviceSpec(const DeviceOptions& options) {
  return DeviceSpecFor(options.device);
}

int DefaultDeviceIndex(const std::vector<DeviceInfo>& devices) {
  // Unavailable devices (busy, no compiler) are a last resort.
  for (const bool need_available : {true, false}) {
    for (const DeviceInfo& d : devices) {
      if (d.type == DeviceType::kGpu && (d.available || !need_available)) return d.index;
    }
    for (const DeviceInfo& d : devices) {
      if (d.IsPoclCpu() && (d.available || !need_available)) return d.index;
    }
  }
  if (devices.empty()) throw NoDeviceError(kNoPlatformMessage);
  return devices.front().index;
}

int SelectDeviceIndex(const std::vector<DeviceInfo>& devices, const DeviceOptions& options) {
  const DeviceSpec spec = EffectiveDeviceSpec(options);
  if (spec.value.empty()) return DefaultDeviceIndex(devices);
  const std::string origin = " (from " + spec.source + ")";
  if (IsIndexSpec(spec.value)) {
    unsigned long long index = 0;  // NOLINT(runtime/int): from_chars' natural type.
    const char* end = spec.value.data() + spec.value.size();
    const auto [ptr, ec] = std::from_chars(spec.value.data(), end, index);
    if (ec == std::errc() && ptr == end && index < devices.size()) {
      return static_cast<int>(index);
    }
    throw NoDeviceError("OpenCL device index " + spec.value + origin +
                        " is out of range; available: " + DeviceList(devices));
  }
  const std::string needle = ToLower(spec.value);
  for (const DeviceInfo& device : devices) {
    if (ToLower(device.MatchText()).find(needle) != std::string::npos) return device.index;
  }
  throw NoDeviceError("no OpenCL device matches \"" + spec.value + "\"" + origin +
                      "; available: " + DeviceList(devices));
}

}  // namespace sapmvs

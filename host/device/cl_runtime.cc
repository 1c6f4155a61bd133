#include "device/cl_runtime.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <stdexcept>

#include "device/kernel_source.h"

namespace sapmvs {
namespace {

DeviceInfo SelectedDevice(const DeviceOptions& options) {
  if (!options.Check()) {
    throw Error("invalid --device \"" + options.device +
                "\": expected a device index (0, 1, ...) or part of a device name");
  }
  const std::vector<DeviceInfo> devices = ListDevices();
  return devices[SelectDeviceIndex(devices, options)];
}

std::string LaunchContext(const ClKernel& kernel, const DeviceInfo& device) {
  return "cannot launch kernel " + kernel.name() + " on " + device.name + ": ";
}

}  // namespace

// ---------------------------------------------------------------------------

void ClEvent::Wait() const {
  const cl_event event = event_.get();
  if (event != nullptr) CL_CHECK(clWaitForEvents(1, &event));
}

uint64_t ClEvent::DeviceTimeNs() const {
  if (!profiling_) {
    throw Error(
        "device timing needs a profiling queue; create the ClContext with "
        "DeviceOptions::profile = true");
  }
  Wait();
  cl_ulong start = 0;
  cl_ulong end = 0;
  CL_CHECK(clGetEventProfilingInfo(event_.get(), CL_PROFILING_COMMAND_START, sizeof(start), &start,
                                   nullptr));
  CL_CHECK(
      clGetEventProfilingInfo(event_.get(), CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr));
  return end >= start ? end - start : 0;
}

namespace {
std::atomic<size_t> device_bytes_in_use{0};
std::atomic<size_t> device_bytes_peak{0};
}  // namespace

namespace internal {
DeviceBytesCount::DeviceBytesCount(size_t bytes) : bytes_(bytes) {
  const size_t now = device_bytes_in_use += bytes;
  size_t peak = device_bytes_peak.load();
  while (now > peak && !device_bytes_peak.compare_exchange_weak(peak, now)) {
  }
}
DeviceBytesCount::~DeviceBytesCount() { device_bytes_in_use -= bytes_; }
DeviceBytesCount& DeviceBytesCount::operator=(DeviceBytesCount&& o) noexcept {
  if (this != &o) {
    device_bytes_in_use -= bytes_;
    bytes_ = o.bytes_;
    o.bytes_ = 0;
  }
  return *this;
}
}  // namespace internal

double DeviceBytesInUse() { return static_cast<double>(device_bytes_in_use.load()); }
double PeakDeviceBytes() { return static_cast<double>(device_bytes_peak.load()); }
void ResetPeakDeviceBytes() { device_bytes_peak = device_bytes_in_use.load(); }

ClBuffer ClBuffer::ReadOnlyInPlace(const ClContext& context, const void* host, size_t bytes) {
  if (host == nullptr) throw Error("cannot create an OpenCL buffer over no host memory");
  // OpenCL's signature is not const; CL_MEM_READ_ONLY keeps kernels from
  // writing to it.
  return ClBuffer(context, bytes, CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, const_cast<void*>(host));
}

ClBuffer::ClBuffer(const ClContext& context, size_t bytes, cl_mem_flags flags)
    : ClBuffer(context, bytes, flags, nullptr) {}

ClBuffer::ClBuffer(const ClContext& context, size_t bytes, cl_mem_flags flags, void* host)
    : size_(bytes) {
  if (bytes == 0) throw Error("cannot create an empty OpenCL buffer (0 bytes)");
  if (bytes > context.device().max_alloc_bytes) {
    throw Error("OpenCL buffer of " + std::to_string(bytes) + " bytes exceeds " +
                context.device().name + "'s CL_DEVICE_MAX_MEM_ALLOC_SIZE of " +
                std::to_string(context.device().max_alloc_bytes) + " bytes");
  }
  cl_int status = CL_SUCCESS;
  mem_ = internal::ClHandle<cl_mem>(clCreateBuffer(context.context(), flags, bytes, host, &status));
  if (status != CL_SUCCESS) {
    throw ClError(status, "clCreateBuffer", __FILE__, __LINE__, std::to_string(bytes) + " bytes");
  }
  CL_CHECK(clRetainCommandQueue(context.queue()));
  queue_ = internal::ClHandle<cl_command_queue>(context.queue());
  // Over host memory on a device that shares it, the kernels read the
  // caller's bytes: nothing is held apart from the process's own memory.
  const bool shared = (flags & CL_MEM_USE_HOST_PTR) && context.device().host_unified_memory;
  if (!shared) count_ = internal::DeviceBytesCount(bytes);
}

void ClBuffer::CheckRange(const char* what, size_t bytes, size_t offset) const {
  if (!mem_) throw std::logic_error(std::string(what) + " on a default-constructed ClBuffer");
  if (offset > size_ || bytes > size_ - offset) {
    throw Error(std::string(what) + " of " + std::to_string(bytes) + " bytes at offset " +
                std::to_string(offset) + " does not fit an OpenCL buffer of " +
                std::to_string(size_) + " bytes");
  }
}

void ClBuffer::Write(const void* host, size_t bytes, size_t offset) {
  CheckRange("write", bytes, offset);
  if (bytes == 0) return;  // A zero-size transfer is CL_INVALID_VALUE.
  CL_CHECK(clEnqueueWriteBuffer(queue_.get(), mem_.get(), CL_TRUE, offset, bytes, host, 0, nullptr,
                                nullptr));
}

void ClBuffer::Read(void* host, size_t bytes, size_t offset) const {
  CheckRange("read", bytes, offset);
  if (bytes == 0) return;
  CL_CHECK(clEnqueueReadBuffer(queue_.get(), mem_.get(), CL_TRUE, offset, bytes, host, 0, nullptr,
                               nullptr));
}

std::string NDRange::ToString() const {
  std::string text = std::to_string(sizes[0]);
  for (cl_uint d = 1; d < dims; ++d) text += "x" + std::to_string(sizes[d]);
  return text;
}

// ---------------------------------------------------------------------------

ClKernel::ClKernel(const ClProgram& program, const std::string& name)
    : name_(name), program_name_(program.name()) {
  cl_int status = CL_SUCCESS;
  kernel_ = internal::ClHandle<cl_kernel>(clCreateKernel(program.get(), name.c_str(), &status));
  if (status != CL_SUCCESS) {
    throw ClError(status, "clCreateKernel", __FILE__, __LINE__,
                  "kernel \"" + name + "\" in program \"" + program.name() + "\"");
  }
  CL_CHECK(
      clGetKernelInfo(kernel_.get(), CL_KERNEL_NUM_ARGS, sizeof(num_args_), &num_args_, nullptr));
}

void ClKernel::CheckArgCount(size_t count) const {
  if (count != num_args_) {
    throw std::logic_error("kernel " + name_ + " takes " + std::to_string(num_args_) +
                           " arguments; SetArgs got " + std::to_string(count));
  }
}

void ClKernel::SetRawArg(cl_uint index, size_t size, const void* value, const char* kind) {
  const cl_int status = clSetKernelArg(kernel_.get(), index, size, value);
  if (status != CL_SUCCESS) {
    throw ClError(status, "clSetKernelArg", __FILE__, __LINE__,
                  "argument " + std::to_string(index) + " (" + kind + ", " + std::to_string(size) +
                      " bytes) of kernel " + name_ + " in program \"" + program_name_ + "\"");
  }
}

size_t ClKernel::MaxWorkGroupSize(cl_device_id device) const {
  size_t size = 0;
  CL_CHECK(clGetKernelWorkGroupInfo(kernel_.get(), device, CL_KERNEL_WORK_GROUP_SIZE, sizeof(size),
                                    &size, nullptr));
  return size;
}

std::array<size_t, 3> ClKernel::RequiredWorkGroupSize(cl_device_id device) const {
  std::array<size_t, 3> size{};
  CL_CHECK(clGetKernelWorkGroupInfo(kernel_.get(), device, CL_KERNEL_COMPILE_WORK_GROUP_SIZE,
                                    sizeof(size), size.data(), nullptr));
  return size;
}

uint64_t ClKernel::LocalMemBytes(cl_device_id device) const {
  cl_ulong bytes = 0;
  CL_CHECK(clGetKernelWorkGroupInfo(kernel_.get(), device, CL_KERNEL_LOCAL_MEM_SIZE, sizeof(bytes),
                                    &bytes, nullptr));
  return bytes;
}

ClProgram::ClProgram(cl_context context, cl_device_id device, std::string name,
                     std::string_view source, std::string options)
    : ClProgram(std::move(name), std::move(options)) {
  const char* text = source.data();
  const size_t length = source.size();
  cl_int status = CL_SUCCESS;
  program_ = internal::ClHandle<cl_program>(
      clCreateProgramWithSource(context, 1, &text, &length, &status));
  if (status != CL_SUCCESS) {
    throw ClError(status, "clCreateProgramWithSource", __FILE__, __LINE__, "program " + name_);
  }
  Build(device);
}

ClProgram ClProgram::FromBinary(cl_context context, cl_device_id device, std::string name,
                                const std::vector<unsigned char>& binary, std::string options) {
  ClProgram program(std::move(name), std::move(options));
  const unsigned char* bytes = binary.data();
  const size_t length = binary.size();
  cl_int binary_status = CL_SUCCESS;
  cl_int status = CL_SUCCESS;
  program.program_ = internal::ClHandle<cl_program>(
      clCreateProgramWithBinary(context, 1, &device, &length, &bytes, &binary_status, &status));
  if (status == CL_SUCCESS) status = binary_status;
  if (status != CL_SUCCESS) {
    throw ClError(status, "clCreateProgramWithBinary", __FILE__, __LINE__,
                  "program " + program.name_);
  }
  program.Build(device);
  program.from_binary_ = true;
  return program;
}

std::vector<unsigned char> ClProgram::Binary() const {
  size_t size = 0;
  if (clGetProgramInfo(program_.get(), CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, nullptr) !=
          CL_SUCCESS ||
      size == 0) {
    return {};
  }
  std::vector<unsigned char> binary(size);
  unsigned char* bytes = binary.data();
  if (clGetProgramInfo(program_.get(), CL_PROGRAM_BINARIES, sizeof(bytes), &bytes, nullptr) !=
      CL_SUCCESS) {
    return {};
  }
  return binary;
}

void ClProgram::Build(cl_device_id device) {
  const cl_int build_status =
      clBuildProgram(program_.get(), 1, &device, options_.c_str(), nullptr, nullptr);
  size_t log_size = 0;
  if (clGetProgramBuildInfo(program_.get(), device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &log_size) ==
      CL_SUCCESS) {
    std::string log(log_size, '\0');
    if (clGetProgramBuildInfo(program_.get(), device, CL_PROGRAM_BUILD_LOG, log_size, log.data(),
                              nullptr) == CL_SUCCESS) {
      build_log_ = CleanInfoString(std::move(log));
    }
  }
  if (build_status != CL_SUCCESS) {
    throw ProgramBuildError(build_status, name_, options_, build_log_, __FILE__, __LINE__);
  }
}

BuildOptions::BuildOptions(std::initializer_list<std::pair<std::string, std::string>> defines) {
  for (const auto& [name, value] : defines) Define(name, value);
}

BuildOptions& BuildOptions::Define(const std::string& name, const std::string& value) {
  const auto is_ident = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  };
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), is_ident)) {
    throw std::invalid_argument("build define name \"" + name + "\" is not a C identifier");
  }
  const auto is_bad = [](char c) {
    return std::isspace(static_cast<unsigned char>(c)) || c == '"' || c == '\'' || c == '\\';
  };
  if (value.empty() || std::any_of(value.begin(), value.end(), is_bad)) {
    throw std::invalid_argument("build define " + name + "=\"" + value +
                                "\" must be non-empty without spaces, quotes or backslashes");
  }
  defines_[name] = value;
  return *this;
}

BuildOptions& BuildOptions::Define(const std::string& name, float value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", static_cast<double>(value));
  std::string literal(text);
  // %g drops the point of whole numbers, and "15f" is not a C literal.
  if (literal.find_first_of(".eEni") == std::string::npos) literal += ".0";
  return Define(name, literal + "f");
}

std::string BuildOptions::Render() const {
  // No -cl-fast-relaxed-math or -cl-finite-math-only: the kernels signal
  // "no value" with NaN and test for it, which those flags may compile away.
  std::string options = "-cl-std=CL1.2";
  for (const auto& [name, value] : defines_) options += " -D " + name + "=" + value;
  return options;
}

// ---------------------------------------------------------------------------

ClContext::ClContext(const DeviceOptions& options)
    : ClContext(SelectedDevice(options), options.profile,
                ProgramBinaryCache(ProgramCacheFolder(options.program_cache))) {}

ClContext::ClContext(const DeviceInfo& device, bool profile, ProgramBinaryCache binaries)
    : device_(device), profiling_(profile), binaries_(std::move(binaries)) {
  if (device.id == nullptr || device.platform_id == nullptr) {
    throw std::invalid_argument("ClContext needs a DeviceInfo from ListDevices()");
  }
  const cl_context_properties properties[] = {
      CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(device.platform_id), 0};
  cl_int status = CL_SUCCESS;
  context_ = internal::ClHandle<cl_context>(
      clCreateContext(properties, 1, &device.id, nullptr, nullptr, &status));
  if (status != CL_SUCCESS) {
    throw ClError(status, "clCreateContext", __FILE__, __LINE__, "device " + device.Describe());
  }
  const cl_command_queue_properties queue_properties = profile ? CL_QUEUE_PROFILING_ENABLE : 0;
  for (internal::ClHandle<cl_command_queue>& queue : queues_) {
    queue = internal::ClHandle<cl_command_queue>(
        clCreateCommandQueue(context_.get(), device.id, queue_properties, &status));
    if (status != CL_SUCCESS) {
      throw ClError(status, "clCreateCommandQueue", __FILE__, __LINE__,
                    "device " + device.Describe());
    }
  }
}

namespace {
// The calling thread's lease: which context, which of its queues.
thread_local const ClContext* lease_context = nullptr;
thread_local int lease_lane = 0;
}  // namespace

ClContext::QueueLease::QueueLease(ClContext& context) : context_(context) {
  std::lock_guard<std::mutex> lock(*context_.mutex_);
  for (int q = 1; q <= kLanes; ++q) {
    if (!context_.leased_[q] && context_.queues_[q]) {
      context_.leased_[q] = true;
      lane_ = q;
      break;
    }
  }
  if (lane_ > 0) {
    lease_context = &context_;
    lease_lane = lane_;
  }
}

ClContext::QueueLease::~QueueLease() {
  if (lane_ == 0) return;
  lease_context = nullptr;
  lease_lane = 0;
  std::lock_guard<std::mutex> lock(*context_.mutex_);
  context_.leased_[lane_] = false;
}

cl_command_queue ClContext::queue() const {
  return queues_[lease_context == this ? lease_lane : 0].get();
}

ClContext::~ClContext() { Release(); }

ClContext& ClContext::operator=(ClContext&& other) noexcept {
  if (this != &other) {
    Release();
    device_ = std::move(other.device_);
    profiling_ = other.profiling_;
    binaries_ = std::move(other.binaries_);
    context_ = std::move(other.context_);
    queues_ = std::move(other.queues_);
    leased_ = other.leased_;
    mutex_ = std::move(other.mutex_);
    programs_mutex_ = std::move(other.programs_mutex_);
    programs_ = std::move(other.programs_);
  }
  return *this;
}

void ClContext::Release() noexcept {
  for (const internal::ClHandle<cl_command_queue>& queue : queues_) {
    if (!queue) continue;
    const cl_int status = clFinish(queue.get());
    if (status != CL_SUCCESS) internal::LogClFailure(status, "clFinish", __FILE__, __LINE__);
  }
  programs_.clear();
  for (internal::ClHandle<cl_command_queue>& queue : queues_) queue.Reset();
  context_.Reset();
}

const ClProgram& ClContext::Program(std::string_view kernel_file, const BuildOptions& defines) {
  return CachedProgram(kernel_file, defines, std::nullopt);
}

const ClProgram& ClContext::ProgramFromSource(std::string_view name, std::string_view source,
                                              const BuildOptions& defines) {
  return CachedProgram(name, defines, source);
}

const ClProgram& ClContext::CachedProgram(std::string_view name, const BuildOptions& defines,
                                          std::optional<std::string_view> source) {
  CacheKey key{device_.id, std::string(name), defines.Render()};
  // A caller's source must match the cached program's; a kernel file's is
  // the file's, loaded below on a miss.
  const bool given = source.has_value();
  const size_t source_hash = given ? std::hash<std::string_view>{}(*source) : 0;
  const auto cached = [&]() -> const ClProgram* {
    const auto it = programs_.find(key);
    if (it == programs_.end()) return nullptr;
    if (given && source_hash != it->second.source_hash) {
      throw std::logic_error("OpenCL program name \"" + std::string(name) +
                             "\" reused for a different source");
    }
    return it->second.program.get();
  };
  {
    std::lock_guard<std::mutex> lock(*programs_mutex_);
    if (const ClProgram* program = cached()) return *program;
  }
  // Built outside the lock: a GPU driver's compiler takes a second or more
  // per program on a cold cache, and the variants build on several threads
  // (PatchKernels::Prepare). Two threads missing the same key both build;
  // the first to finish is kept.
  std::string loaded;
  if (!given) {
    loaded = ProgramSource(name);
    source = loaded;
  }
  CacheEntry entry;
  entry.source_hash = given ? source_hash : std::hash<std::string_view>{}(*source);
  entry.program = BuildOrLoad(std::get<1>(key), *source, std::get<2>(key));
  std::lock_guard<std::mutex> lock(*programs_mutex_);
  if (const ClProgram* program = cached()) return *program;
  return *programs_.emplace(std::move(key), std::move(entry)).first->second.program;
}

std::unique_ptr<ClProgram> ClContext::BuildOrLoad(const std::string& name, std::string_view source,
                                                  const std::string& options) const {
  if (!binaries_.enabled()) {
    return std::make_unique<ClProgram>(context_.get(), device_.id, name, source, options);
  }
  const std::string key = ProgramCacheKey(device_, options, source);
  if (const std::optional<std::vector<unsigned char>> binary = binaries_.Load(key)) {
    try {
      return std::make_unique<ClProgram>(
          ClProgram::FromBinary(context_.get(), device_.id, name, *binary, options));
    } catch (const std::exception&) {  // refused by the driver: built below, stored anew
    }
  }
  auto program = std::make_unique<ClProgram>(context_.get(), device_.id, name, source, options);
  binaries_.Store(key, program->Binary());
  return program;
}

ClEvent ClContext::Enqueue(const ClKernel& kernel, const NDRange& global, const NDRange& local) {
  if (kernel.get() == nullptr) throw std::logic_error("Enqueue of a default-constructed ClKernel");
  const std::string context = LaunchContext(kernel, device_);
  if (global.dims != local.dims) {
    throw Error(context + "global size " + global.ToString() + " and work-group size " +
                local.ToString() + " differ in dimensions");
  }
  if (local.Total() > device_.max_work_group_size) {
    throw Error(context + "work-group size " + local.ToString() + " (" +
                std::to_string(local.Total()) +
                " work-items) exceeds the device's CL_DEVICE_MAX_WORK_GROUP_SIZE of " +
                std::to_string(device_.max_work_group_size));
  }
  for (cl_uint d = 0; d < local.dims; ++d) {
    if (global.sizes[d] == 0 || local.sizes[d] == 0) {
      throw Error(context + "empty global size " + global.ToString() + " or work-group size " +
                  local.ToString());
    }
    if (d >= device_.max_work_item_sizes.size() ||
        local.sizes[d] > device_.max_work_item_sizes[d]) {
      throw Error(context + "work-group size " + local.ToString() + " exceeds the device's " +
                  "CL_DEVICE_MAX_WORK_ITEM_SIZES in dimension " + std::to_string(d));
    }
  }
  if (const size_t kernel_max = kernel.MaxWorkGroupSize(device_.id); local.Total() > kernel_max) {
    throw Error(context + "work-group size " + local.ToString() + " (" +
                std::to_string(local.Total()) +
                " work-items) exceeds this kernel's CL_KERNEL_WORK_GROUP_SIZE of " +
                std::to_string(kernel_max) + " on this device");
  }
  if (const auto required = kernel.RequiredWorkGroupSize(device_.id); required[0] != 0) {
    for (cl_uint d = 0; d < 3; ++d) {
      if (local.sizes[d] != required[d]) {
        throw Error(context + "work-group size " + local.ToString() +
                    " differs from the kernel's reqd_work_group_size " +
                    NDRange(required[0], required[1], required[2]).ToString() +
                    " it was built for");
      }
    }
  }
  if (const uint64_t bytes = kernel.LocalMemBytes(device_.id); bytes > device_.local_mem_bytes) {
    throw Error(context + "needs " + std::to_string(bytes) +
                " bytes of local memory; the device has " +
                std::to_string(device_.local_mem_bytes));
  }

  NDRange rounded = global;
  for (cl_uint d = 0; d < global.dims; ++d) {
    rounded.sizes[d] = (global.sizes[d] + local.sizes[d] - 1) / local.sizes[d] * local.sizes[d];
  }
  cl_event event = nullptr;
  const cl_int status =
      clEnqueueNDRangeKernel(queue(), kernel.get(), global.dims, nullptr, rounded.sizes.data(),
                             local.sizes.data(), 0, nullptr, &event);
  if (status != CL_SUCCESS) {
    throw ClError(status, "clEnqueueNDRangeKernel", __FILE__, __LINE__,
                  "kernel " + kernel.name() + ", global " + rounded.ToString() + ", local " +
                      local.ToString());
  }
  return ClEvent(event, profiling_);
}

void ClContext::Finish() const {
  for (const internal::ClHandle<cl_command_queue>& queue : queues_) {
    if (queue) CL_CHECK(clFinish(queue.get()));
  }
}

}  // namespace sapmvs

#pragma once
// The OpenCL runtime layer: one context on the device cl_devices.h selects,
// with in-order queues, thin RAII wrappers over the C API (movable, not
// copyable, in the manner of CLBlast's clpp11) and a program cache. Every
// kernel launch goes through ClContext::Enqueue, which checks work-group
// limits first so a bad launch fails with a sentence rather than
// CL_INVALID_WORK_GROUP_SIZE.
//
// Two host threads may share a ClContext only as the patch kernels do: each
// in a queue lease (ClContext::LeaseQueue), launching through
// ClContext::Launch on objects that both only read, after one thread made
// them. Nothing else here is thread-safe.

#include <CL/cl.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "device/cl_devices.h"
#include "device/cl_error.h"
#include "device/program_binary_cache.h"

namespace sapmvs {

// ---------------------------------------------------------------------------
// RAII handles.

namespace internal {

template <typename T>
struct ClTraits;

#define SAPMVS_CL_TRAITS(type, release)                   \
  template <>                                             \
  struct ClTraits<type> {                                 \
    static cl_int Release(type h) { return release(h); }  \
    static constexpr const char* kReleaseName = #release; \
  }
SAPMVS_CL_TRAITS(cl_context, clReleaseContext);
SAPMVS_CL_TRAITS(cl_command_queue, clReleaseCommandQueue);
SAPMVS_CL_TRAITS(cl_mem, clReleaseMemObject);
SAPMVS_CL_TRAITS(cl_program, clReleaseProgram);
SAPMVS_CL_TRAITS(cl_kernel, clReleaseKernel);
SAPMVS_CL_TRAITS(cl_event, clReleaseEvent);
#undef SAPMVS_CL_TRAITS

// Owns one reference to an OpenCL object.
template <typename T>
class ClHandle {
 public:
  ClHandle() = default;
  explicit ClHandle(T handle) : handle_(handle) {}
  ~ClHandle() { Reset(); }
  ClHandle(const ClHandle&) = delete;
  ClHandle& operator=(const ClHandle&) = delete;
  ClHandle(ClHandle&& other) noexcept : handle_(std::exchange(other.handle_, nullptr)) {}
  ClHandle& operator=(ClHandle&& other) noexcept {
    if (this != &other) {
      Reset();
      handle_ = std::exchange(other.handle_, nullptr);
    }
    return *this;
  }

  T get() const { return handle_; }
  explicit operator bool() const { return handle_ != nullptr; }

  void Reset() noexcept {
    if (handle_ == nullptr) return;
    const cl_int status = ClTraits<T>::Release(handle_);
    if (status != CL_SUCCESS) {
      LogClFailure(status, ClTraits<T>::kReleaseName, __FILE__, __LINE__);
    }
    handle_ = nullptr;
  }

 private:
  T handle_ = nullptr;
};

}  // namespace internal

class ClContext;
class ClProgram;

// A completed or pending command.
class ClEvent {
 public:
  ClEvent() = default;
  // Takes ownership of `event`. `profiling` tells whether its queue profiles.
  ClEvent(cl_event event, bool profiling) : event_(event), profiling_(profiling) {}

  cl_event get() const { return event_.get(); }
  bool profiling() const { return profiling_; }
  void Wait() const;
  // Device execution time (CL_PROFILING_COMMAND_END - START) in nanoseconds;
  // waits for the command first. Throws Error unless the context was created
  // with DeviceOptions::profile.
  uint64_t DeviceTimeNs() const;

 private:
  internal::ClHandle<cl_event> event_;
  bool profiling_ = false;
};

// A device buffer. Write/Read are blocking and go through the context's queue
// (the buffer keeps its own reference to it).
namespace internal {
// Counts a buffer's bytes as device memory in use while it lives
// (DeviceBytesInUse); moves with the buffer.
class DeviceBytesCount {
 public:
  DeviceBytesCount() = default;
  explicit DeviceBytesCount(size_t bytes);
  ~DeviceBytesCount();
  DeviceBytesCount(DeviceBytesCount&& o) noexcept : bytes_(o.bytes_) { o.bytes_ = 0; }
  DeviceBytesCount& operator=(DeviceBytesCount&& o) noexcept;
  DeviceBytesCount(const DeviceBytesCount&) = delete;
  DeviceBytesCount& operator=(const DeviceBytesCount&) = delete;

 private:
  size_t bytes_ = 0;
};
}  // namespace internal

// Bytes of the OpenCL buffers alive in this process, now and at their peak
// since ResetPeakDeviceBytes: what the device holds for us, which on a CPU
// device is also part of the process's RSS.
double DeviceBytesInUse();
double PeakDeviceBytes();
void ResetPeakDeviceBytes();

class ClBuffer {
 public:
  ClBuffer() = default;
  // Throws Error for 0 bytes or more than the device's max allocation.
  ClBuffer(const ClContext& context, size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE);
  // A read-only buffer over `bytes` of host memory at `host`
  // (CL_MEM_USE_HOST_PTR), which must outlive it and stay unchanged: on a
  // device with host_unified_memory the kernels read it in place, and it is
  // not counted in DeviceBytesInUse.
  static ClBuffer ReadOnlyInPlace(const ClContext& context, const void* host, size_t bytes);

  cl_mem get() const { return mem_.get(); }
  size_t size() const { return size_; }  // Bytes.

  // Copy `bytes` between host memory and [offset, offset + bytes) of the
  // buffer. Throws Error when the range does not fit.
  void Write(const void* host, size_t bytes, size_t offset = 0);
  void Read(void* host, size_t bytes, size_t offset = 0) const;

  // Typed helpers; `offset` is in bytes. ReadVector reads values->size()
  // elements. (Named apart from Write/Read so `Read(&v, n)` cannot silently
  // mean "n bytes" to one reader and "offset n" to another.)
  template <typename T>
  void WriteVector(const std::vector<T>& values, size_t offset = 0) {
    static_assert(std::is_trivially_copyable_v<T>, "buffer elements must be trivially copyable");
    Write(values.data(), values.size() * sizeof(T), offset);
  }
  template <typename T>
  void ReadVector(std::vector<T>* values, size_t offset = 0) const {
    static_assert(std::is_trivially_copyable_v<T>, "buffer elements must be trivially copyable");
    Read(values->data(), values->size() * sizeof(T), offset);
  }

 private:
  ClBuffer(const ClContext& context, size_t bytes, cl_mem_flags flags, void* host);
  void CheckRange(const char* what, size_t bytes, size_t offset) const;

  internal::ClHandle<cl_mem> mem_;
  internal::ClHandle<cl_command_queue> queue_;
  size_t size_ = 0;
  internal::DeviceBytesCount count_;
};

// A `__local` kernel argument of `bytes` bytes, for ClKernel::SetArgs.
struct LocalMem {
  size_t bytes = 0;
};

// A launch size of 1 to 3 dimensions, in work-items. Implicit from one size_t
// so 1-D launches read `Enqueue(kernel, n, 64)`.
struct NDRange {
  NDRange(size_t x) : dims(1), sizes{x, 1, 1} {}  // NOLINT(runtime/explicit)
  NDRange(size_t x, size_t y) : dims(2), sizes{x, y, 1} {}
  NDRange(size_t x, size_t y, size_t z) : dims(3), sizes{x, y, z} {}

  size_t Total() const { return sizes[0] * sizes[1] * sizes[2]; }
  std::string ToString() const;  // "64" or "16x16".

  cl_uint dims;
  std::array<size_t, 3> sizes;
};

class ClKernel {
 public:
  ClKernel() = default;
  // Throws ClError (CL_INVALID_KERNEL_NAME) naming the kernel and program.
  ClKernel(const ClProgram& program, const std::string& name);

  cl_kernel get() const { return kernel_.get(); }
  const std::string& name() const { return name_; }
  cl_uint num_args() const { return num_args_; }

  // Sets all arguments in order. Each is a ClBuffer, a LocalMem or a trivially
  // copyable scalar/vector (cl_int, cl_float, cl_float2, ...) whose size must
  // match the kernel's parameter; a mismatch throws naming the argument.
  template <typename... Args>
  void SetArgs(const Args&... args) {
    CheckArgCount(sizeof...(Args));
    cl_uint index = 0;
    (SetArg(index++, args), ...);
  }

  template <typename T>
  void SetArg(cl_uint index, const T& value) {
    if constexpr (std::is_same_v<T, ClBuffer>) {
      const cl_mem mem = value.get();
      SetRawArg(index, sizeof(cl_mem), &mem, "buffer");
    } else if constexpr (std::is_same_v<T, LocalMem>) {
      SetRawArg(index, value.bytes, nullptr, "local memory");
    } else {
      static_assert(std::is_trivially_copyable_v<T> && !std::is_pointer_v<T>,
                    "kernel arguments are ClBuffer, LocalMem or plain values");
      static_assert(!std::is_same_v<T, bool>, "bool is not a valid OpenCL kernel argument");
      SetRawArg(index, sizeof(T), &value, "value");
    }
  }

  // CL_KERNEL_WORK_GROUP_SIZE: the largest work-group this kernel can run
  // with on `device` (may be below the device maximum, e.g. register use).
  size_t MaxWorkGroupSize(cl_device_id device) const;
  // The kernel's reqd_work_group_size attribute, or {0, 0, 0} without one.
  std::array<size_t, 3> RequiredWorkGroupSize(cl_device_id device) const;
  // CL_KERNEL_LOCAL_MEM_SIZE in bytes, including LocalMem arguments set so far.
  uint64_t LocalMemBytes(cl_device_id device) const;

 private:
  void CheckArgCount(size_t count) const;
  void SetRawArg(cl_uint index, size_t size, const void* value, const char* kind);

  internal::ClHandle<cl_kernel> kernel_;
  std::string name_;
  std::string program_name_;
  cl_uint num_args_ = 0;
};

// A built program. Obtain through ClContext::Program so builds are cached.
class ClProgram {
 public:
  // Builds `source` for `device`; throws ProgramBuildError with the full log.
  ClProgram(cl_context context, cl_device_id device, std::string name, std::string_view source,
            std::string options);
  // Loads `binary`, which Binary() gave for the same device, driver, options
  // and source. Throws ClError or ProgramBuildError when the driver refuses
  // it (another driver's, damaged).
  static ClProgram FromBinary(cl_context context, cl_device_id device, std::string name,
                              const std::vector<unsigned char>& binary, std::string options);

  cl_program get() const { return program_.get(); }
  const std::string& name() const { return name_; }
  const std::string& options() const { return options_; }
  const std::string& build_log() const { return build_log_; }  // Warnings, if any.
  bool from_binary() const { return from_binary_; }
  // The device's binary of the program (CL_PROGRAM_BINARIES); empty when the
  // driver gives none.
  std::vector<unsigned char> Binary() const;

  ClKernel Kernel(const std::string& kernel_name) const { return ClKernel(*this, kernel_name); }

 private:
  ClProgram(std::string name, std::string options)
      : name_(std::move(name)), options_(std::move(options)) {}
  // clBuildProgram, keeping the log; throws ProgramBuildError.
  void Build(cl_device_id device);

  internal::ClHandle<cl_program> program_;
  std::string name_;
  std::string options_;
  std::string build_log_;
  bool from_binary_ = false;
};

// `-D NAME=VALUE` defines for a program build, rendered sorted by name so
// equal sets give equal option strings (and so hit the same cache entry).
class BuildOptions {
 public:
  BuildOptions() = default;
  BuildOptions(std::initializer_list<std::pair<std::string, std::string>> defines);

  // Throws std::invalid_argument unless `name` is a C identifier and `value`
  // is non-empty without whitespace or quotes (options are split on spaces).
  BuildOptions& Define(const std::string& name, const std::string& value);
  template <typename T, typename = std::enable_if_t<std::is_integral_v<T>>>
  BuildOptions& Define(const std::string& name, T value) {
    return Define(name, std::to_string(value));
  }
  // A float literal that parses back to exactly `value` in OpenCL C
  // ("%.9gf": 9 significant digits round-trip every float).
  BuildOptions& Define(const std::string& name, float value);

  const std::map<std::string, std::string>& defines() const { return defines_; }
  // The complete option string: "-cl-std=CL1.2 -D A=1 -D B=2".
  std::string Render() const;

 private:
  std::map<std::string, std::string> defines_;
};

// The selected device's context, its in-order queue and kLanes more, plus
// the program cache. Movable; programs handed out stay valid while it lives.
class ClContext {
 public:
  // Queues besides the main one that leases hand out.
  static constexpr int kLanes = 2;

  // While it lives, the launches and buffer copies its thread makes on its
  // context go to a queue no other lease holds, not to the main queue (to
  // the main queue when every lane is leased). On one in-order queue, two
  // host threads' launches ran one after the other, and a launch's last
  // work-groups left PoCL's other threads idle; on two queues the device
  // runs both (PoCL's threads take the work-groups of either; a GPU
  // overlaps the kernels). Not movable; one per thread at a time.
  class QueueLease {
   public:
    ~QueueLease();
    QueueLease(const QueueLease&) = delete;
    QueueLease& operator=(const QueueLease&) = delete;

   private:
    friend class ClContext;
    explicit QueueLease(ClContext& context);
    ClContext& context_;
    int lane_ = 0;  // an index into queues_; 0, the main queue, is never leased
  };
  // Selects a device as described in DeviceOptions. Throws NoDeviceError.
  explicit ClContext(const DeviceOptions& options = DeviceOptions());
  // `binaries`: where built programs are kept between processes (none by
  // default).
  ClContext(const DeviceInfo& device, bool profile, ProgramBinaryCache binaries = {});
  // Waits for the queue (Finish) before releasing the programs, the queue and
  // the context, in that order. A command still in flight at release can
  // leave a driver thread working (PoCL compiles a kernel's work-group
  // function when it first runs) while the process exits and tears down the
  // compiler under it.
  ~ClContext();
  ClContext(ClContext&& other) noexcept = default;
  ClContext& operator=(ClContext&& other) noexcept;
  ClContext(const ClContext&) = delete;
  ClContext& operator=(const ClContext&) = delete;

  const DeviceInfo& device() const { return device_; }
  cl_device_id device_id() const { return device_.id; }
  cl_context context() const { return context_.get(); }
  // The calling thread's queue: its lease's lane, else the main queue.
  cl_command_queue queue() const;
  QueueLease LeaseQueue() { return QueueLease(*this); }
  bool profiling() const { return profiling_; }

  // The program built from kernels/<kernel_file> (see KernelSource) with
  // `defines`; built on first use (or loaded from the binary cache), then
  // cached by (device, name, options).
  // Thread-safe; several threads build different programs at once.
  const ClProgram& Program(std::string_view kernel_file, const BuildOptions& defines = {});
  // Same, from a source string (tests, generated code). `name` must identify
  // the source: reusing it with different source for the same options throws
  // std::logic_error rather than returning a stale program.
  const ClProgram& ProgramFromSource(std::string_view name, std::string_view source,
                                     const BuildOptions& defines = {});
  size_t NumCachedPrograms() const {
    std::lock_guard<std::mutex> lock(*programs_mutex_);
    return programs_.size();
  }

  // The one launch path. Checks `local` against the device and the kernel
  // (work-group size, work-item sizes, reqd_work_group_size, local memory) and
  // throws Error before enqueueing if it cannot run; rounds `global` up to a
  // multiple of `local`, so the kernel must bounds-check its global id.
  ClEvent Enqueue(const ClKernel& kernel, const NDRange& global, const NDRange& local);
  // kernel.SetArgs(args...) and Enqueue as one step under the context's
  // lock: a kernel's arguments are its own state until the enqueue copies
  // them, so two threads launching one kernel must not interleave the two.
  template <typename... Args>
  ClEvent Launch(ClKernel& kernel, const NDRange& global, const NDRange& local,
                 const Args&... args) {
    std::lock_guard<std::mutex> lock(*mutex_);
    kernel.SetArgs(args...);
    return Enqueue(kernel, global, local);
  }

  // Blocks until every command queued on any of its queues has finished.
  void Finish() const;

 private:
  using CacheKey = std::tuple<cl_device_id, std::string, std::string>;
  struct CacheEntry {
    size_t source_hash = 0;
    std::unique_ptr<ClProgram> program;
  };
  // `source` empty: load kernels/<name> on a cache miss.
  const ClProgram& CachedProgram(std::string_view name, const BuildOptions& defines,
                                 std::optional<std::string_view> source);
  // A program from `source`: the binary cache's when it has a usable one,
  // else built from source, and then stored there.
  std::unique_ptr<ClProgram> BuildOrLoad(const std::string& name, std::string_view source,
                                         const std::string& options) const;
  // Finish, then release in order; leaves the object empty. Never throws.
  void Release() noexcept;

  DeviceInfo device_;
  bool profiling_ = false;
  ProgramBinaryCache binaries_;
  internal::ClHandle<cl_context> context_;
  // The main queue at 0, the lanes after it.
  std::array<internal::ClHandle<cl_command_queue>, 1 + kLanes> queues_;
  std::array<bool, 1 + kLanes> leased_{};
  // Guards leased_ and Launch; a pointer so that the context stays movable.
  std::unique_ptr<std::mutex> mutex_ = std::make_unique<std::mutex>();
  // Guards programs_ (not held while a program builds); a pointer likewise.
  std::unique_ptr<std::mutex> programs_mutex_ = std::make_unique<std::mutex>();
  std::map<CacheKey, CacheEntry> programs_;
};

}  // namespace sapmvs

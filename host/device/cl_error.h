#pragma once
// Errors from the OpenCL C API. Every API call goes through CL_CHECK so that a
// failure names the status (not just its number), the call as written and where
// it was made; a bare "-54" in a bug report is useless.

#include <CL/cl.h>

#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {

// The symbolic name of an OpenCL status code, e.g. "CL_INVALID_KERNEL_ARGS".
// Covers every OpenCL 1.2 code plus the later core and common extension codes a
// newer driver may return; anything else reads "CL_UNKNOWN_STATUS(<code>)".
std::string ClStatusName(cl_int status);

// An OpenCL call returned something other than CL_SUCCESS. what() reads
// "CL_INVALID_WORK_GROUP_SIZE (-54) in clEnqueueNDRangeKernel(...) at
// host/device/cl_runtime.cc:123", optionally followed by ": <detail>".
class ClError : public Error {
 public:
  ClError(cl_int status, const std::string& call, const char* file, int line,
          const std::string& detail = "");

  cl_int status() const { return status_; }
  const std::string& status_name() const { return status_name_; }
  const std::string& call() const { return call_; }
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  cl_int status_;
  std::string status_name_;
  std::string call_;
  std::string file_;
  int line_;
};

// clBuildProgram failed. what() carries the program name, the exact build
// options and the complete compiler log, because the log is the only thing
// that tells a kernel author what went wrong.
class ProgramBuildError : public ClError {
 public:
  ProgramBuildError(cl_int status, const std::string& program_name, const std::string& options,
                    const std::string& build_log, const char* file, int line);

  const std::string& program_name() const { return program_name_; }
  const std::string& options() const { return options_; }
  const std::string& build_log() const { return build_log_; }

 private:
  std::string program_name_;
  std::string options_;
  std::string build_log_;
};

namespace internal {
// Writes one line to stderr for a failed call. For destructors, which must not
// throw: a failed release is worth a note but not worth terminating for.
void LogClFailure(cl_int status, const char* call, const char* file, int line) noexcept;
}  // namespace internal

}  // namespace sapmvs

// Evaluates an OpenCL call returning cl_int and throws sapmvs::ClError unless
// it returned CL_SUCCESS.
#define CL_CHECK(call)                                                       \
  do {                                                                       \
    const cl_int sapmvs_cl_status_ = (call);                                 \
    if (sapmvs_cl_status_ != CL_SUCCESS) {                                   \
      throw ::sapmvs::ClError(sapmvs_cl_status_, #call, __FILE__, __LINE__); \
    }                                                                        \
  } while (0)

// Like CL_CHECK but only logs; for destructors and other noexcept paths.
#define CL_CHECK_LOG(call)                                                            \
  do {                                                                                \
    const cl_int sapmvs_cl_status_ = (call);                                          \
    if (sapmvs_cl_status_ != CL_SUCCESS) {                                            \
      ::sapmvs::internal::LogClFailure(sapmvs_cl_status_, #call, __FILE__, __LINE__); \
    }                                                                                 \
  } while (0)

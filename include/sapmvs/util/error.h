#pragma once
// The error types that reach the user. Each message is one line that names the
// file, line or value at fault and what was expected; the CLI prints it as is
// and exits with the code the type carries.

#include <stdexcept>
#include <string>

namespace sapmvs {

// Bad input or a failed operation the user can act on. Exit code 1.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
  virtual int ExitCode() const { return 1; }
};

// Malformed input file: "FILE:LINE: expected ..., got ...".
class InputError : public Error {
 public:
  InputError(const std::string& file, int line, const std::string& message)
      : Error(line > 0 ? file + ":" + std::to_string(line) + ": " + message
                       : file + ": " + message),
        file_(file),
        line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

// No OpenCL platform or no usable device. Exit code 2, so scripts can tell a
// missing runtime from bad input.
class NoDeviceError : public Error {
 public:
  explicit NoDeviceError(const std::string& what) : Error(what) {}
  int ExitCode() const override { return 2; }
};

}  // namespace sapmvs

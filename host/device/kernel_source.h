#pragma once
// Where kernel source comes from. Release binaries carry kernels/*.cl inside
// them (cmake/EmbedKernels.cmake), so an installed `sapmvs` never depends on
// the source tree. For kernel development, SAPMVS_KERNEL_DIR=<dir> makes every
// lookup read <dir>/<file> from disk instead, so an edited kernel is picked up
// without rebuilding the host.

#include <string>
#include <string_view>
#include <vector>

namespace sapmvs {

// The source of kernels/<file>, e.g. KernelSource("bilinear_sample.cl"): from
// $SAPMVS_KERNEL_DIR/<file> when that variable is set and non-empty, else the
// embedded copy. Throws Error naming the file (and the available files, or the
// path that could not be read).
std::string KernelSource(std::string_view file);

// The embedded copy only, ignoring SAPMVS_KERNEL_DIR. Throws like KernelSource.
std::string EmbeddedKernelSource(std::string_view file);

// The source a program is built from: KernelSource(file) with every line
// `#include "other.cl"` replaced by ProgramSource("other.cl"), between #line
// directives so that build logs name the right file and line. This is how
// kernels share primitives (ncc.cl, bilinear.cl) while each file stays valid
// OpenCL C: the embedded sources have no file system for the device
// compiler's own #include. Throws Error naming the including file and line
// for an unknown file, and for includes nested deeper than 8 (a cycle).
std::string ProgramSource(std::string_view file);

// Names of the embedded kernel files, sorted.
std::vector<std::string> EmbeddedKernelFiles();

}  // namespace sapmvs

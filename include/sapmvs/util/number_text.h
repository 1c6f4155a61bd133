#pragma once
// Numbers as the text formats and reports write them, in one place so that
// each writer states its precision rather than keeping its own copy.
#include <limits>
#include <string>

namespace sapmvs {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// `v` as printf's %.<digits>g: 17 digits round-trip a double, 12 keep
// millimetres of a UTM coordinate, 10 suit reports.
std::string FormatNumber(double v, int digits);

// `v` through one printf conversion (`format` takes one double).
std::string FormatPrintf(const char* format, double v);

}  // namespace sapmvs

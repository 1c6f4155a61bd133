#include "sapmvs/util/number_text.h"

#include <sstream>

#include <cstdio>

namespace sapmvs {

std::string FormatNumber(double v, int digits) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

std::string FormatPrintf(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace sapmvs

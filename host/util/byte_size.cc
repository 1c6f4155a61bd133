#include "sapmvs/util/byte_size.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {

double ParseByteSize(const std::string& text) {
  const auto fail = [&] {
    return Error("bad memory size '" + text +
                 "': expected a positive number of bytes or a size such as 8G, 512M, 1.5G");
  };
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw fail();
  }
  if (used == 0 || (!std::isdigit(static_cast<unsigned char>(text[0])) && text[0] != '.'))
    throw fail();
  std::string unit = text.substr(used);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  double scale = 1;
  if (!unit.empty() && std::string("KMGT").find(unit[0]) != std::string::npos) {
    scale = std::pow(1024.0, 1 + std::string("KMGT").find(unit[0]));
    unit.erase(0, 1);
    if (unit == "IB") unit.erase(0, 1);
  }
  if (!(unit.empty() || unit == "B")) throw fail();
  value *= scale;
  if (!(value > 0 && std::isfinite(value))) throw fail();
  return value;
}

std::string FormatBytes(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (std::abs(bytes) >= 1024 && u < 4) {
    bytes /= 1024;
    ++u;
  }
  // Three significant digits: "8 GiB", "1.5 GiB", "57.1 MiB", "123 MiB".
  char buf[64];
  if (bytes >= 100 || u == 0)
    std::snprintf(buf, sizeof(buf), "%.0f %s", bytes, units[u]);
  else
    std::snprintf(buf, sizeof(buf), "%.3g %s", bytes, units[u]);
  return buf;
}

}  // namespace sapmvs

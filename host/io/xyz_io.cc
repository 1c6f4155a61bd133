// XYZ text clouds (declared in las_io.h with the LAS ones): what is easy to
// inspect and to script.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "sapmvs/io/las_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "util/text_lines.h"

namespace sapmvs {
namespace {

void CheckPoints(const std::filesystem::path& path, const std::vector<PointRecord>& points) {
  for (size_t i = 0; i < points.size(); ++i) {
    const PointRecord& p = points[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw Error(path.string() + ": point " + std::to_string(i) + " is (" + FormatNumber(p.x, 12) +
                  ", " + FormatNumber(p.y, 12) + ", " + FormatNumber(p.z, 12) +
                  "); expected finite coordinates");
    }
  }
}

}  // namespace

void WriteXyz(const std::filesystem::path& path, const std::vector<PointRecord>& points,
              int precision, bool rgb) {
  if (precision < 0 || precision > 17) {
    throw Error(path.string() + ": XYZ precision " + std::to_string(precision) +
                " (expected 0-17 decimals)");
  }
  CheckPoints(path, points);
  WriteStreamAtomically(path, [&](std::ostream& out) {
    char line[256];
    for (const PointRecord& p : points) {
      int n = std::snprintf(line, sizeof line, "%.*f %.*f %.*f", precision, p.x, precision, p.y,
                            precision, p.z);
      if (rgb && n > 0 && n < static_cast<int>(sizeof line)) {
        n += std::snprintf(line + n, sizeof line - n, " %d %d %d", ColorTo8(p.r), ColorTo8(p.g),
                           ColorTo8(p.b));
      }
      if (n < 0 || n >= static_cast<int>(sizeof line)) {
        throw Error(path.string() + ": point (" + FormatNumber(p.x, 12) + ", " +
                    FormatNumber(p.y, 12) + ", " + FormatNumber(p.z, 12) +
                    ") does not fit an XYZ line");
      }
      line[n] = '\n';
      out.write(line, n + 1);
    }
  });
}

XyzCloud ReadXyz(const std::filesystem::path& path) {
  TextLines lines(path);
  XyzCloud cloud;
  std::string line;
  size_t fields = 0;
  int layout_line = 0;
  constexpr const char* kNames[6] = {"X", "Y", "Z", "R", "G", "B"};
  while (lines.NextRaw(&line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    const std::vector<std::string> tokens = SplitWhitespace(line);
    if (tokens.empty()) continue;
    if (fields == 0) {
      if (tokens.size() != 3 && tokens.size() != 6) {
        throw lines.Fail("expected 3 fields (X Y Z) or 6 (X Y Z R G B), got " +
                         std::to_string(tokens.size()));
      }
      fields = tokens.size();
      layout_line = lines.line();
      cloud.has_rgb = fields == 6;
    } else if (tokens.size() != fields) {
      throw lines.Fail("expected " + std::to_string(fields) + " fields like line " +
                       std::to_string(layout_line) + ", got " + std::to_string(tokens.size()));
    }
    PointRecord p;
    p.x = lines.Double(tokens[0], kNames[0]);
    p.y = lines.Double(tokens[1], kNames[1]);
    p.z = lines.Double(tokens[2], kNames[2]);
    if (cloud.has_rgb) {
      uint16_t* channel[3] = {&p.r, &p.g, &p.b};
      for (int c = 0; c < 3; ++c) {
        const int v = lines.Int(tokens[3 + c], kNames[3 + c]);
        if (v < 0 || v > 255) {
          throw lines.Fail("expected 8-bit colour 0-255 for " + std::string(kNames[3 + c]) +
                           ", got " + tokens[3 + c]);
        }
        *channel[c] = ColorTo16(static_cast<uint8_t>(v));
      }
    }
    cloud.points.push_back(p);
  }
  return cloud;
}

}  // namespace sapmvs

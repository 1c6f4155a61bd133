#include "sapmvs/io/ply_stream.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Points per write call: a few MB at most.
constexpr size_t kPlyWriteChunk = 1 << 16;

std::string PlyHeaderText(const PointCloud& format, const PlyCounts& counts, size_t* record) {
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by sapmvs\n";
  if (!format.crs.empty()) {
    std::string crs = format.crs;
    std::replace_if(
        crs.begin(), crs.end(), [](char c) { return c == '\n' || c == '\r'; }, ' ');
    header << "comment crs " << crs << "\n";
  }
  header << "element vertex " << counts.count << "\n"
         << "property double x\nproperty double y\nproperty double z\n";
  *record = 24;
  if (format.has_normals) {
    header << "property float nx\nproperty float ny\nproperty float nz\n";
    *record += 12;
  }
  if (format.has_colors) {
    header << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    *record += 3;
  }
  if (format.has_scores) {
    header << "property float scalar_score\n";
    *record += 4;
  }
  if (format.has_views) {
    header << "property " << (counts.views_fit_uchar ? "uchar" : "int") << " scalar_views\n";
    *record += counts.views_fit_uchar ? 1 : 4;
  }
  header << "end_header\n";
  return header.str();
}

}  // namespace

void PlyCounts::Add(const std::string& file, const CloudPoint& p, bool has_views) {
  if (!p.position.allFinite()) {
    throw Error(file + ": point " + std::to_string(count) +
                " has a non-finite coordinate (expected finite x y z)");
  }
  if (has_views && p.num_views < 0) {
    throw Error(file + ": point " + std::to_string(count) + " has " + std::to_string(p.num_views) +
                " views (expected a count >= 0)");
  }
  views_fit_uchar = views_fit_uchar && p.num_views <= 255;
  ++count;
}

void WritePlyStream(const std::filesystem::path& path, const PointCloud& format,
                    const PlyCounts& counts, const NextPoints& next) {
  size_t record = 0;
  const std::string header = PlyHeaderText(format, counts, &record);
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    std::vector<uint8_t> buffer;
    size_t written = 0;
    for (PointSpan chunk = next(); chunk.size > 0; chunk = next()) {
      if (written + chunk.size > counts.count) {
        written += chunk.size;  // more than declared: refused below
        break;
      }
      for (size_t first = 0; first < chunk.size; first += kPlyWriteChunk) {
        const size_t n = std::min(kPlyWriteChunk, chunk.size - first);
        buffer.resize(n * record);
        uint8_t* b = buffer.data();
        auto put = [&b](const void* v, size_t size) {
          std::memcpy(b, v, size);
          b += size;
        };
        for (size_t i = first; i < first + n; ++i) {
          const CloudPoint& p = chunk.data[i];
          put(p.position.data(), 24);
          if (format.has_normals) put(p.normal.data(), 12);
          if (format.has_colors) put(p.color.data(), 3);
          if (format.has_scores) put(&p.score, 4);
          if (format.has_views) {
            if (counts.views_fit_uchar) {
              const uint8_t v = static_cast<uint8_t>(p.num_views);
              put(&v, 1);
            } else {
              const int32_t v = p.num_views;
              put(&v, 4);
            }
          }
        }
        out.write(reinterpret_cast<const char*>(buffer.data()),
                  static_cast<std::streamsize>(buffer.size()));
      }
      written += chunk.size;
    }
    if (written != counts.count) {
      throw Error(path.string() + ": " + std::to_string(counts.count) +
                  " points declared, more or fewer given (expected the same points twice)");
    }
  });
}

void WritePly(const std::filesystem::path& path, const PointCloud& cloud) {
  PlyCounts counts;
  for (const CloudPoint& p : cloud.points) counts.Add(path.string(), p, cloud.has_views);
  bool given = false;
  WritePlyStream(path, cloud, counts, [&] {
    const PointSpan all{cloud.points.data(), given ? 0 : cloud.points.size()};
    given = true;
    return all;
  });
}

}  // namespace sapmvs

#include "sapmvs/io/las_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>
#include <utility>

#include "io/las_extra_bytes.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "util/input_file.h"

namespace sapmvs {
namespace {

// LAS is little-endian; fields are copied as-is.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "LAS I/O needs byte swapping here");

constexpr size_t kHeaderSize12 = 227, kHeaderSize14 = 375;
constexpr size_t kVlrHeaderSize = 54;
constexpr size_t kEvlrHeaderSize = 60;
constexpr char kProjectionUserId[] = "LASF_Projection";
constexpr uint16_t kWktRecordId = 2112, kGeoKeyRecordId = 34735;
constexpr uint16_t kWktEncodingBit = 1u << 4;
constexpr int kMaxFormat = 10;
// Bytes each point format needs, and where its RGB starts (-1: none).
constexpr size_t kMinRecordLength[kMaxFormat + 1] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
constexpr int kRgbOffset[kMaxFormat + 1] = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};
// Records per read or write call: large enough to amortise the calls, small
// enough that the buffer stays a few MB even for 67-byte records.
constexpr size_t kChunkPoints = 1 << 16;
// Quantized coordinates stay one below the int32 limit so rounding never
// overflows.
constexpr double kMaxQuantized = 2147483646.0;

template <typename T>
T Get(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <typename T>
void Put(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

// Both the writer (for the header's bounding box) and the reader go from
// quantized to world coordinates with this, so the box matches what is read.
double Dequantize(int32_t q, double scale, double offset) {
  return static_cast<double>(q) * scale + offset;
}

// 10^exponent as the double nearest the decimal (0.001, not 0.001 * 10 * 10),
// so that headers show round scales.
double DecimalScale(int exponent) {
  double p = 1;
  for (int i = 0; i < std::abs(exponent); ++i) p *= 10;  // exact up to 1e22
  return exponent < 0 ? 1 / p : p;
}

struct Quantization {
  std::array<double, 3> scale{}, offset{}, lo{}, hi{};
};

Quantization ChooseQuantization(const std::filesystem::path& path, const LasCounts& counts,
                                double user_scale, bool geographic) {
  constexpr const char* kAxis[3] = {"X", "Y", "Z"};
  Quantization q;
  if (counts.count == 0) {
    q.scale.fill(user_scale > 0 ? user_scale : 0.001);
    return q;
  }
  for (int a = 0; a < 3; ++a) {
    const double lo = counts.lo[a], hi = counts.hi[a];
    q.offset[a] = std::round(0.5 * lo + 0.5 * hi);  // lo + hi may overflow
    const double reach = std::max(hi - q.offset[a], q.offset[a] - lo);
    if (user_scale > 0) {
      q.scale[a] = user_scale;
      if (reach / user_scale > kMaxQuantized) {
        throw Error(path.string() + ": " + kAxis[a] + " spans " + FormatNumber(lo, 12) + " to " +
                    FormatNumber(hi, 12) + ", too wide for scale " + FormatNumber(user_scale, 12) +
                    " in int32 (expected a scale >= " + FormatNumber(reach / kMaxQuantized, 12) +
                    ")");
      }
    } else {
      // ~1 cm on the ground for degrees; mm for metres.
      int exponent = geographic && a < 2 ? -7 : -3;
      while (reach / DecimalScale(exponent) > kMaxQuantized) ++exponent;
      q.scale[a] = DecimalScale(exponent);
    }
  }
  return q;
}

int32_t Quantize(double v, double scale, double offset) {
  return static_cast<int32_t>(std::llround((v - offset) / scale));
}

// The point format each version is written in.
int WriteFormat(LasVersion v) { return v == LasVersion::k12 ? 2 : 7; }

std::vector<uint8_t> MakeHeader(const LasCounts& counts, const Quantization& q, size_t vlr_bytes,
                                uint32_t vlr_count, size_t record_length,
                                const LasWriteOptions& options) {
  const bool v12 = options.version == LasVersion::k12;
  const size_t size = v12 ? kHeaderSize12 : kHeaderSize14;
  std::vector<uint8_t> h(size, 0);
  std::memcpy(h.data(), "LASF", 4);
  if (!v12) Put<uint16_t>(&h[6], kWktEncodingBit);
  h[24] = 1;
  h[25] = v12 ? 2 : 4;
  std::snprintf(reinterpret_cast<char*>(&h[26]), 32, "%s", "OTHER");
  std::snprintf(reinterpret_cast<char*>(&h[58]), 32, "sapmvs %s", SAPMVS_VERSION);
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  Put<uint16_t>(&h[90], static_cast<uint16_t>(options.creation_day > 0 ? options.creation_day
                                                                       : utc.tm_yday + 1));
  Put<uint16_t>(&h[92], static_cast<uint16_t>(options.creation_year > 0 ? options.creation_year
                                                                        : utc.tm_year + 1900));
  Put<uint16_t>(&h[94], static_cast<uint16_t>(size));
  Put<uint32_t>(&h[96], static_cast<uint32_t>(size + vlr_bytes));
  Put<uint32_t>(&h[100], vlr_count);
  h[104] = static_cast<uint8_t>(WriteFormat(options.version));
  Put<uint16_t>(&h[105], static_cast<uint16_t>(record_length));
  const auto& by_return = counts.by_return;
  // LAS 1.4 forbids the legacy counts (bytes 107-130) for formats 6-10; LAS
  // 1.2 has only them, returns 1-5.
  if (v12) {
    Put<uint32_t>(&h[107], static_cast<uint32_t>(counts.count));
    for (int r = 0; r < 5; ++r) Put<uint32_t>(&h[111 + 4 * r], static_cast<uint32_t>(by_return[r]));
  }
  for (int a = 0; a < 3; ++a) {
    Put<double>(&h[131 + 8 * a], q.scale[a]);
    Put<double>(&h[155 + 8 * a], q.offset[a]);
    Put<double>(&h[179 + 16 * a], q.hi[a]);
    Put<double>(&h[187 + 16 * a], q.lo[a]);
  }
  if (!v12) {
    Put<uint64_t>(&h[247], counts.count);
    for (int r = 0; r < 15; ++r) Put<uint64_t>(&h[255 + 8 * r], by_return[r]);
  }
  return h;
}

void AppendVlr(const std::filesystem::path& path, const char* user_id, uint16_t record_id,
               const char* description, const std::vector<uint8_t>& payload,
               std::vector<uint8_t>* out) {
  if (payload.size() > std::numeric_limits<uint16_t>::max()) {
    throw Error(path.string() + ": " + description + " takes " + std::to_string(payload.size()) +
                " bytes; expected at most 65535 to fit a LAS VLR");
  }
  std::vector<uint8_t> v(kVlrHeaderSize, 0);
  std::memcpy(&v[2], user_id, std::strlen(user_id));
  Put<uint16_t>(&v[18], record_id);
  Put<uint16_t>(&v[20], static_cast<uint16_t>(payload.size()));
  std::snprintf(reinterpret_cast<char*>(&v[22]), 32, "%s", description);
  out->insert(out->end(), v.begin(), v.end());
  out->insert(out->end(), payload.begin(), payload.end());
}

// GeoTIFF keys (the GeoKeyDirectoryTag, LAS 1.2's way to give the CRS) for a
// CRS with an EPSG code, projected or geographic, with its vertical CRS when
// that has one; empty for any other CRS, which then has only its WKT.
std::vector<uint8_t> GeoKeys(const WktFacts& crs) {
  const bool projected = crs.projected;
  if (!projected && !crs.geographic) return {};
  const int h = crs.horizontal_epsg;
  if (h <= 0 || h > 65535) return {};
  // {key, location 0 = the value itself, count 1, value}, by key.
  std::vector<std::array<uint16_t, 4>> keys = {
      {1024, 0, 1, static_cast<uint16_t>(projected ? 1 : 2)},  // GTModelType
      {1025, 0, 1, 1},                                         // GTRasterType: PixelIsArea
      {static_cast<uint16_t>(projected ? 3072 : 2048), 0, 1, static_cast<uint16_t>(h)}};
  if (const int v = crs.vertical_epsg; v > 0 && v <= 65535) {
    keys.push_back({4096, 0, 1, static_cast<uint16_t>(v)});  // VerticalCSType
  }
  std::vector<uint8_t> out(8 * (keys.size() + 1));
  const uint16_t directory[4] = {1, 1, 0, static_cast<uint16_t>(keys.size())};
  std::memcpy(out.data(), directory, 8);
  for (size_t k = 0; k < keys.size(); ++k) std::memcpy(&out[8 * (k + 1)], keys[k].data(), 8);
  return out;
}

void EncodePoint(const PointRecord& p, const Quantization& q, int format, uint8_t* out) {
  Put<int32_t>(out + 0, Quantize(p.x, q.scale[0], q.offset[0]));
  Put<int32_t>(out + 4, Quantize(p.y, q.scale[1], q.offset[1]));
  Put<int32_t>(out + 8, Quantize(p.z, q.scale[2], q.offset[2]));
  Put<uint16_t>(out + 12, p.intensity);
  if (format < 6) {
    out[14] = static_cast<uint8_t>((p.return_number & 0x07) | ((p.number_of_returns & 0x07) << 3));
    out[15] = p.classification & 0x1F;
  } else {
    out[14] = static_cast<uint8_t>((p.return_number & 0x0F) | (p.number_of_returns << 4));
    out[16] = p.classification;
  }
  Put<uint16_t>(out + kRgbOffset[format], p.r);
  Put<uint16_t>(out + kRgbOffset[format] + 2, p.g);
  Put<uint16_t>(out + kRgbOffset[format] + 4, p.b);
}

void DecodePoint(const uint8_t* p, int format, const LasCloud& cloud, PointRecord* out) {
  out->x = Dequantize(Get<int32_t>(p + 0), cloud.scale[0], cloud.offset[0]);
  out->y = Dequantize(Get<int32_t>(p + 4), cloud.scale[1], cloud.offset[1]);
  out->z = Dequantize(Get<int32_t>(p + 8), cloud.scale[2], cloud.offset[2]);
  out->intensity = Get<uint16_t>(p + 12);
  if (format < 6) {
    out->return_number = p[14] & 0x07;
    out->number_of_returns = (p[14] >> 3) & 0x07;
    out->classification = p[15] & 0x1F;
  } else {
    out->return_number = p[14] & 0x0F;
    out->number_of_returns = p[14] >> 4;
    out->classification = p[16];
  }
  if (kRgbOffset[format] >= 0) {
    out->r = Get<uint16_t>(p + kRgbOffset[format]);
    out->g = Get<uint16_t>(p + kRgbOffset[format] + 2);
    out->b = Get<uint16_t>(p + kRgbOffset[format] + 4);
  }
}

bool IsRecord(const uint8_t* record_header, const char* user_id, uint16_t record_id) {
  return las::FixedString(record_header + 2, 16) == user_id &&
         Get<uint16_t>(record_header + 18) == record_id;
}
bool IsWktRecord(const uint8_t* h) { return IsRecord(h, kProjectionUserId, kWktRecordId); }
bool IsExtraBytesRecord(const uint8_t* h) {
  return IsRecord(h, las::kSpecUserId, las::kExtraBytesRecordId);
}

// Reads `n` bytes at `pos`; the caller has checked that they lie in the file.
std::vector<uint8_t> ReadAt(std::ifstream& in, uint64_t pos, size_t n, const std::string& file) {
  std::vector<uint8_t> buf(n);
  in.seekg(static_cast<std::streamoff>(pos));
  in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n));
  if (static_cast<size_t>(in.gcount()) != n) {
    throw InputError(file, 0, "read failed at byte " + std::to_string(pos));
  }
  return buf;
}

std::string WktFromPayload(const std::vector<uint8_t>& payload) {
  return las::FixedString(payload.data(), payload.size());
}

}  // namespace

LasVersion ParseLasVersion(const std::string& text) {
  if (text == "1.2") return LasVersion::k12;
  if (text == "1.4") return LasVersion::k14;
  throw Error("LAS version '" + text + "' (--las-version): expected 1.2 or 1.4");
}

std::string ToString(LasVersion version) { return version == LasVersion::k12 ? "1.2" : "1.4"; }

std::string LasWriteOptions::Problem() const {
  if (!(scale >= 0) || !std::isfinite(scale)) {
    return "LAS scale " + FormatNumber(scale, 12) +
           ": expected a positive resolution, or 0 to choose one";
  }
  if (creation_day < 0 || creation_day > 366 || creation_year < 0 || creation_year > 65535) {
    return "LAS creation day " + std::to_string(creation_day) + " / year " +
           std::to_string(creation_year) + ": expected day 1-366 and a year, or 0 for today";
  }
  try {
    CrsToWkt(crs);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

void LasCounts::Add(const std::filesystem::path& path, const PointRecord& p, LasVersion version) {
  const bool v12 = version == LasVersion::k12;
  const int max_return = v12 ? 7 : 15;
  const std::string at = path.string() + ": point " + std::to_string(count);
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
    throw Error(at + " is (" + FormatNumber(p.x, 12) + ", " + FormatNumber(p.y, 12) + ", " +
                FormatNumber(p.z, 12) + "); expected finite coordinates");
  }
  if (p.return_number > max_return || p.number_of_returns > max_return) {
    throw Error(at + " has return " + std::to_string(p.return_number) + " of " +
                std::to_string(p.number_of_returns) + "; expected at most " +
                std::to_string(max_return) + " in LAS " + ToString(version));
  }
  if (v12 && p.classification > 31) {
    throw Error(at + " has class " + std::to_string(p.classification) +
                "; expected at most 31 in LAS 1.2 (LAS 1.4 holds up to 255)");
  }
  const double v[3] = {p.x, p.y, p.z};
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::min(lo[a], v[a]);
    hi[a] = std::max(hi[a], v[a]);
  }
  if (p.return_number >= 1) ++by_return[p.return_number - 1];
  ++count;
}

void WidenExtraRanges(const std::filesystem::path& path, const std::vector<LasExtraField>& chunk,
                      size_t points, std::vector<LasExtraField>* ranges) {
  if (const std::string problem = las::ExtraFieldsProblem(chunk, points); !problem.empty()) {
    throw Error(path.string() + ": " + problem);
  }
  if (ranges->empty()) {
    for (const LasExtraField& f : chunk) ranges->push_back({f.name, f.description, f.type, {}});
  }
  for (size_t k = 0; k < chunk.size() && k < ranges->size(); ++k) {
    std::vector<double>& r = (*ranges)[k].values;
    for (const double v : chunk[k].values) {
      if (r.empty()) {
        r = {v, v};
      } else {
        r[0] = std::min(r[0], v);
        r[1] = std::max(r[1], v);
      }
    }
  }
}

void WriteLasStream(const std::filesystem::path& path, const LasCounts& counts,
                    const LasWriteOptions& options, const std::vector<LasExtraField>& ranges,
                    const NextLasPoints& next) {
  if (const std::string problem = options.Problem(); !problem.empty()) {
    throw Error(path.string() + ": " + problem);
  }
  if (options.version == LasVersion::k12 && counts.count > std::numeric_limits<uint32_t>::max()) {
    throw Error(path.string() + ": " + std::to_string(counts.count) +
                " points; LAS 1.2 holds at most 4294967295 (use LAS 1.4)");
  }
  const std::string wkt = CrsToWkt(options.crs);
  const WktFacts facts = wkt.empty() ? WktFacts{} : ReadWktFacts(wkt);
  Quantization q = ChooseQuantization(path, counts, options.scale, facts.geographic);
  // The stored (quantized) extent: quantizing and back is monotonic, so the
  // extremes of the stored coordinates are those of the given ones.
  for (int a = 0; a < 3 && counts.count > 0; ++a) {
    auto stored = [&](double v) {
      return Dequantize(Quantize(v, q.scale[a], q.offset[a]), q.scale[a], q.offset[a]);
    };
    q.lo[a] = stored(counts.lo[a]);
    q.hi[a] = stored(counts.hi[a]);
  }
  std::vector<uint8_t> vlrs;
  uint32_t vlr_count = 0;
  if (options.version == LasVersion::k12) {
    if (const std::vector<uint8_t> keys = GeoKeys(facts); !keys.empty()) {
      AppendVlr(path, kProjectionUserId, kGeoKeyRecordId, "GeoTIFF GeoKeyDirectoryTag", keys,
                &vlrs);
      ++vlr_count;
    }
  }
  if (!wkt.empty()) {
    // The spec asks for a terminating NUL.
    AppendVlr(path, kProjectionUserId, kWktRecordId, "OGC WKT coordinate system",
              std::vector<uint8_t>(wkt.c_str(), wkt.c_str() + wkt.size() + 1), &vlrs);
    ++vlr_count;
  }
  if (!ranges.empty()) {
    AppendVlr(path, las::kSpecUserId, las::kExtraBytesRecordId, "Extra Bytes",
              las::EncodeExtraDescriptors(ranges), &vlrs);
    ++vlr_count;
  }
  const int format = WriteFormat(options.version);
  const size_t base = kMinRecordLength[format];
  size_t record = base;
  for (const LasExtraField& f : ranges) record += las::ExtraTypeSize(f.type);
  const std::vector<uint8_t> header =
      MakeHeader(counts, q, vlrs.size(), vlr_count, record, options);

  WriteStreamAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(header.data()), header.size());
    out.write(reinterpret_cast<const char*>(vlrs.data()), vlrs.size());
    std::vector<uint8_t> buf(kChunkPoints * record);
    const std::vector<PointRecord>* chunk = nullptr;
    const std::vector<LasExtraField>* chunk_extras = nullptr;
    size_t written = 0;
    while (written <= counts.count && next(&chunk, &chunk_extras)) {
      const std::vector<PointRecord>& points = *chunk;
      for (size_t first = 0; first < points.size(); first += kChunkPoints) {
        const size_t n = std::min(kChunkPoints, points.size() - first);
        std::fill(buf.begin(), buf.end(), 0);
        for (size_t i = 0; i < n; ++i) {
          EncodePoint(points[first + i], q, format, &buf[i * record]);
          las::EncodeExtraValues(*chunk_extras, first + i, &buf[i * record + base]);
        }
        out.write(reinterpret_cast<const char*>(buf.data()),
                  static_cast<std::streamsize>(n * record));
      }
      written += points.size();
    }
    if (written != counts.count) {
      throw Error(path.string() + ": " + std::to_string(counts.count) +
                  " points declared, more or fewer given (expected the same points twice)");
    }
  });
}

void WriteLas(const std::filesystem::path& path, const std::vector<PointRecord>& points,
              const LasWriteOptions& options, const std::vector<LasExtraField>& extras) {
  if (const std::string problem = options.Problem(); !problem.empty()) {
    throw Error(path.string() + ": " + problem);
  }
  LasCounts counts;
  for (const PointRecord& p : points) counts.Add(path, p, options.version);
  std::vector<LasExtraField> ranges;
  WidenExtraRanges(path, extras, points.size(), &ranges);
  bool given = false;
  WriteLasStream(
      path, counts, options, ranges,
      [&](const std::vector<PointRecord>** chunk, const std::vector<LasExtraField>** chunk_extras) {
        *chunk = &points;
        *chunk_extras = &extras;
        return !std::exchange(given, true);
      });
}

LasCloud ReadLas(const std::filesystem::path& path, bool extra_values) {
  const std::string file = path.string();
  std::ifstream in = OpenInputFile(path, std::ios::binary);
  const uint64_t size = std::filesystem::file_size(path);
  auto fail = [&](const std::string& message) { return InputError(file, 0, message); };

  std::vector<uint8_t> h(std::min<uint64_t>(size, kHeaderSize14));
  in.read(reinterpret_cast<char*>(h.data()), static_cast<std::streamsize>(h.size()));
  if (h.size() < 4 || std::memcmp(h.data(), "LASF", 4) != 0) {
    throw fail("not a LAS file (expected the signature 'LASF' at byte 0)");
  }
  if (size < 227) {
    throw fail("truncated header: the file has " + std::to_string(size) +
               " bytes, a LAS header needs at least 227");
  }
  LasCloud cloud;
  cloud.version_major = h[24];
  cloud.version_minor = h[25];
  const std::string version =
      std::to_string(cloud.version_major) + "." + std::to_string(cloud.version_minor);
  if (cloud.version_major != 1 || cloud.version_minor > 4) {
    throw fail("unsupported LAS version " + version + " (expected 1.0-1.4)");
  }
  const size_t header_size = Get<uint16_t>(&h[94]);
  const size_t min_header = cloud.version_minor <= 2 ? 227 : cloud.version_minor == 3 ? 235 : 375;
  if (header_size < min_header) {
    throw fail("header size " + std::to_string(header_size) + " is too small for LAS " + version +
               " (expected at least " + std::to_string(min_header) + ")");
  }
  if (header_size > size) {
    throw fail("truncated header: header size " + std::to_string(header_size) + ", file size " +
               std::to_string(size));
  }
  const uint8_t format_byte = h[104];
  // LASzip marks compressed files by setting bit 7 (and in old versions bit 6)
  // of the point format.
  if (format_byte & 0xC0) {
    throw fail("LAZ-compressed point data (format byte " + std::to_string(format_byte) +
               ") is not supported; expected uncompressed LAS (decompress with laszip or "
               "pdal translate)");
  }
  if (format_byte > kMaxFormat) {
    throw fail("unknown point data format " + std::to_string(format_byte) + " (expected 0-10)");
  }
  cloud.point_format = format_byte;
  cloud.has_rgb = kRgbOffset[format_byte] >= 0;
  const size_t record_length = Get<uint16_t>(&h[105]);
  if (record_length < kMinRecordLength[format_byte]) {
    throw fail("point record length " + std::to_string(record_length) +
               " is too short for format " + std::to_string(format_byte) + " (expected at least " +
               std::to_string(kMinRecordLength[format_byte]) + ")");
  }
  const uint64_t point_offset = Get<uint32_t>(&h[96]);
  const uint32_t vlr_count = Get<uint32_t>(&h[100]);
  uint64_t count = Get<uint32_t>(&h[107]);
  if (cloud.version_minor >= 4 && Get<uint64_t>(&h[247]) != 0) count = Get<uint64_t>(&h[247]);
  for (int a = 0; a < 3; ++a) {
    cloud.scale[a] = Get<double>(&h[131 + 8 * a]);
    cloud.offset[a] = Get<double>(&h[155 + 8 * a]);
    if (!std::isfinite(cloud.scale[a]) || cloud.scale[a] == 0 || !std::isfinite(cloud.offset[a])) {
      throw fail("scale " + FormatNumber(cloud.scale[a], 12) + " / offset " +
                 FormatNumber(cloud.offset[a], 12) + " of " + "XYZ"[a] +
                 " (expected a finite, non-zero scale and a finite offset)");
    }
  }
  if (point_offset < header_size || point_offset > size) {
    throw fail("offset to point data " + std::to_string(point_offset) +
               " lies outside the file (expected " + std::to_string(header_size) + " to " +
               std::to_string(size) + ")");
  }
  if (count > (size - point_offset) / record_length) {
    throw fail("truncated point data: the header declares " + std::to_string(count) +
               " points of " + std::to_string(record_length) + " bytes from byte " +
               std::to_string(point_offset) + ", the file has room for " +
               std::to_string((size - point_offset) / record_length));
  }

  uint64_t pos = header_size;
  std::vector<las::ExtraFieldLayout> extra_layout;
  for (uint32_t i = 0; i < vlr_count; ++i) {
    if (pos + kVlrHeaderSize > point_offset) {
      throw fail("variable length record " + std::to_string(i + 1) + " of " +
                 std::to_string(vlr_count) + " runs into the point data at byte " +
                 std::to_string(point_offset));
    }
    const std::vector<uint8_t> vh = ReadAt(in, pos, kVlrHeaderSize, file);
    const uint64_t length = Get<uint16_t>(&vh[20]);
    if (pos + kVlrHeaderSize + length > point_offset) {
      throw fail("variable length record " + std::to_string(i + 1) + " of " +
                 std::to_string(vlr_count) + " runs into the point data at byte " +
                 std::to_string(point_offset));
    }
    if (IsWktRecord(vh.data()) && cloud.crs_wkt.empty()) {
      cloud.crs_wkt = WktFromPayload(ReadAt(in, pos + kVlrHeaderSize, length, file));
    }
    if (IsExtraBytesRecord(vh.data()) && extra_layout.empty()) {
      extra_layout = las::DecodeExtraDescriptors(ReadAt(in, pos + kVlrHeaderSize, length, file),
                                                 record_length - kMinRecordLength[format_byte]);
    }
    pos += kVlrHeaderSize + length;
  }
  if (cloud.version_minor >= 4) {
    pos = Get<uint64_t>(&h[235]);
    const uint32_t evlr_count = Get<uint32_t>(&h[243]);
    for (uint32_t i = 0; i < evlr_count; ++i) {
      if (pos > size || size - pos < kEvlrHeaderSize) {
        throw fail("extended variable length record " + std::to_string(i + 1) + " of " +
                   std::to_string(evlr_count) + " at byte " + std::to_string(pos) +
                   " lies past the end of the file");
      }
      const std::vector<uint8_t> vh = ReadAt(in, pos, kEvlrHeaderSize, file);
      const uint64_t length = Get<uint64_t>(&vh[20]);
      if (length > size - pos - kEvlrHeaderSize) {
        throw fail("extended variable length record " + std::to_string(i + 1) + " of " +
                   std::to_string(evlr_count) + " runs past the end of the file");
      }
      if (IsWktRecord(vh.data()) && cloud.crs_wkt.empty()) {
        cloud.crs_wkt = WktFromPayload(ReadAt(in, pos + kEvlrHeaderSize, length, file));
      }
      pos += kEvlrHeaderSize + length;
    }
  }

  cloud.points.resize(count);
  for (const las::ExtraFieldLayout& f : extra_layout) {
    cloud.extras.push_back(f.field);
    if (extra_values) cloud.extras.back().values.resize(count);
  }
  // No larger than the points the file holds: a record length up to 65,535
  // bytes (extra bytes) times a whole chunk was 4 GB for a 1 kB file (fuzzing).
  std::vector<uint8_t> buf(static_cast<size_t>(std::min<uint64_t>(kChunkPoints, count)) *
                           record_length);
  in.seekg(static_cast<std::streamoff>(point_offset));
  for (uint64_t first = 0; first < count; first += kChunkPoints) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(kChunkPoints, count - first));
    in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n * record_length));
    if (static_cast<size_t>(in.gcount()) != n * record_length) {
      throw fail("read failed in the point data near point " + std::to_string(first));
    }
    for (size_t i = 0; i < n; ++i) {
      const uint8_t* record = &buf[i * record_length];
      DecodePoint(record, format_byte, cloud, &cloud.points[first + i]);
      if (!extra_values) continue;
      for (size_t k = 0; k < extra_layout.size(); ++k) {
        cloud.extras[k].values[first + i] =
            las::DecodeExtraValue(extra_layout[k], record + kMinRecordLength[format_byte]);
      }
    }
  }
  return cloud;
}

}  // namespace sapmvs

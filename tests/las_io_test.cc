#include "sapmvs/io/las_io.h"

#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

class LasIoTest : public test::ScratchTest {};

// Little-endian field access, written independently of las_io.cc so that the
// tests check the bytes against the specification, not against themselves.
template <typename T>
T LeField(const Bytes& b, size_t at) {
  if (at + sizeof(T) > b.size()) throw std::out_of_range("field past the end of the file");
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <typename T>
void SetLeField(Bytes* b, size_t at, T v) {
  if (at + sizeof(T) > b->size()) throw std::out_of_range("field past the end of the file");
  std::memcpy(b->data() + at, &v, sizeof v);
}

Bytes ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& path, const Bytes& b) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

// Points around a UTM zone 32 site: X ~ 5e5, Y ~ 5.4e6, Z ~ 300 m.
std::vector<PointRecord> RandomUtmPoints(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> dx(-1500, 1500), dz(-40, 60);
  std::uniform_int_distribution<int> u16(0, 65535), returns(1, 15), cls(0, 255);
  std::vector<PointRecord> points(n);
  for (PointRecord& p : points) {
    p.x = 5e5 + dx(rng);
    p.y = 5.4e6 + dx(rng);
    p.z = 300 + dz(rng);
    p.r = static_cast<uint16_t>(u16(rng));
    p.g = static_cast<uint16_t>(u16(rng));
    p.b = static_cast<uint16_t>(u16(rng));
    p.intensity = static_cast<uint16_t>(u16(rng));
    p.number_of_returns = static_cast<uint8_t>(returns(rng));
    p.return_number = static_cast<uint8_t>(1 + u16(rng) % p.number_of_returns);
    p.classification = static_cast<uint8_t>(cls(rng));
  }
  return points;
}

// The layout most tests check byte by byte, and the one RandomUtmPoints'
// returns (up to 15) and classes (up to 255) need.
LasWriteOptions V14() {
  LasWriteOptions o;
  o.version = LasVersion::k14;
  return o;
}

// Expects `f` to throw an InputError for `path` (line 0) whose message
// contains `expected`.
template <typename F>
void ExpectInputError(F f, const fs::path& path, const std::string& expected) {
  try {
    f();
    ADD_FAILURE() << "expected an InputError containing '" << expected << "'";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.line(), 0);
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

TEST_F(LasIoTest, RandomUtmPointsRoundTripWithinTheScale) {
  const fs::path path = dir_ / "cloud.las";
  const std::vector<PointRecord> points = RandomUtmPoints(1001, 7);
  WriteLas(path, points, V14());
  const LasCloud cloud = ReadLas(path);
  ASSERT_EQ(cloud.points.size(), points.size());
  EXPECT_EQ(cloud.version_major, 1);
  EXPECT_EQ(cloud.version_minor, 4);
  EXPECT_EQ(cloud.point_format, 7);
  EXPECT_TRUE(cloud.has_rgb);
  EXPECT_TRUE(cloud.crs_wkt.empty());
  for (int a = 0; a < 3; ++a) EXPECT_EQ(cloud.scale[a], 0.001);
  for (size_t i = 0; i < points.size(); ++i) {
    const PointRecord &p = points[i], &q = cloud.points[i];
    // Half the scale, plus the rounding of doubles near 5.4e6 (~1e-9).
    EXPECT_NEAR(q.x, p.x, 0.0005 + 1e-8) << i;
    EXPECT_NEAR(q.y, p.y, 0.0005 + 1e-8) << i;
    EXPECT_NEAR(q.z, p.z, 0.0005 + 1e-8) << i;
    EXPECT_EQ(q.intensity, p.intensity) << i;
    EXPECT_EQ(q.return_number, p.return_number) << i;
    EXPECT_EQ(q.number_of_returns, p.number_of_returns) << i;
    EXPECT_EQ(q.classification, p.classification) << i;
  }
}

TEST_F(LasIoTest, RgbRoundTripsExactly) {
  const fs::path path = dir_ / "rgb.las";
  std::vector<PointRecord> points(5);
  const uint16_t colours[5][3] = {
      {0, 0, 0}, {65535, 65535, 65535}, {1, 2, 3}, {ColorTo16(200), ColorTo16(17), 0}, {257, 0, 9}};
  for (int i = 0; i < 5; ++i) {
    points[i].x = i;
    points[i].r = colours[i][0];
    points[i].g = colours[i][1];
    points[i].b = colours[i][2];
  }
  WriteLas(path, points, V14());
  const LasCloud cloud = ReadLas(path);
  ASSERT_EQ(cloud.points.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(cloud.points[i].r, colours[i][0]);
    EXPECT_EQ(cloud.points[i].g, colours[i][1]);
    EXPECT_EQ(cloud.points[i].b, colours[i][2]);
  }
  EXPECT_EQ(ColorTo8(cloud.points[3].r), 200);
  EXPECT_EQ(ColorTo8(cloud.points[3].g), 17);
}

TEST_F(LasIoTest, CrsRoundTripsAsWktOfTheSameCrs) {
  const fs::path path = dir_ / "utm.las";
  LasWriteOptions options = V14();
  options.crs = "EPSG:32632";
  ASSERT_TRUE(options.Check()) << options.Problem();
  WriteLas(path, RandomUtmPoints(10, 1), options);
  const LasCloud cloud = ReadLas(path);
  ASSERT_FALSE(cloud.crs_wkt.empty());
  OGRSpatialReference expected, got;
  ASSERT_EQ(expected.SetFromUserInput("EPSG:32632"), OGRERR_NONE);
  ASSERT_EQ(got.importFromWkt(cloud.crs_wkt.c_str()), OGRERR_NONE) << cloud.crs_wkt;
  EXPECT_TRUE(got.IsSame(&expected)) << cloud.crs_wkt;
  EXPECT_NE(cloud.crs_wkt.find("32632"), std::string::npos);
}

TEST_F(LasIoTest, HeaderBytesFollowLas14Format7) {
  const fs::path path = dir_ / "header.las";
  const std::vector<PointRecord> points = RandomUtmPoints(93, 3);
  LasWriteOptions options = V14();
  options.crs = "EPSG:32632";
  WriteLas(path, points, options);
  const Bytes b = ReadBytes(path);
  ASSERT_GE(b.size(), 375u);
  EXPECT_EQ(std::string(b.begin(), b.begin() + 4), "LASF");
  EXPECT_EQ(b[24], 1);
  EXPECT_EQ(b[25], 4);
  EXPECT_EQ(LeField<uint16_t>(b, 94), 375);  // header size
  EXPECT_TRUE(LeField<uint16_t>(b, 6) & (1 << 4)) << "WKT bit of the global encoding";
  EXPECT_EQ(b[104], 7);                      // point format
  EXPECT_EQ(LeField<uint16_t>(b, 105), 36);  // record length
  EXPECT_EQ(LeField<uint32_t>(b, 107), 0u);  // legacy count: zero for formats 6-10
  EXPECT_EQ(LeField<uint64_t>(b, 247), 93u);
  EXPECT_EQ(LeField<uint32_t>(b, 243), 0u);  // no EVLRs
  uint64_t by_return_sum = 0;
  for (int r = 0; r < 15; ++r) by_return_sum += LeField<uint64_t>(b, 255 + 8 * r);
  EXPECT_EQ(by_return_sum, 93u);

  // One VLR: LASF_Projection / 2112 carrying NUL-terminated WKT.
  ASSERT_EQ(LeField<uint32_t>(b, 100), 1u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[375 + 2])), "LASF_Projection");
  EXPECT_EQ(LeField<uint16_t>(b, 375 + 18), 2112);
  const size_t vlr_length = LeField<uint16_t>(b, 375 + 20);
  EXPECT_EQ(b[375 + 54 + vlr_length - 1], 0);
  const size_t point_offset = LeField<uint32_t>(b, 96);
  EXPECT_EQ(point_offset, 375 + 54 + vlr_length);
  // GDAL is no LAS reader, so the layout is checked by size.
  EXPECT_EQ(fs::file_size(path), point_offset + 93 * 36);
  EXPECT_EQ(b.size(), point_offset + 93 * 36);

  // Bounding box: max/min per axis at 179 + 16a / 187 + 16a, equal to the
  // extent of the stored points and within half the scale of the input's.
  const LasCloud cloud = ReadLas(path);
  for (int a = 0; a < 3; ++a) {
    auto coord = [a](const PointRecord& p) { return a == 0 ? p.x : a == 1 ? p.y : p.z; };
    auto less = [&](const PointRecord& p, const PointRecord& q) { return coord(p) < coord(q); };
    const auto [in_lo, in_hi] = std::minmax_element(points.begin(), points.end(), less);
    const auto [out_lo, out_hi] =
        std::minmax_element(cloud.points.begin(), cloud.points.end(), less);
    const double scale = LeField<double>(b, 131 + 8 * a);
    EXPECT_EQ(scale, 0.001);
    EXPECT_EQ(LeField<double>(b, 179 + 16 * a), coord(*out_hi)) << a;
    EXPECT_EQ(LeField<double>(b, 187 + 16 * a), coord(*out_lo)) << a;
    EXPECT_NEAR(LeField<double>(b, 179 + 16 * a), coord(*in_hi), scale / 2 + 1e-8) << a;
    EXPECT_NEAR(LeField<double>(b, 187 + 16 * a), coord(*in_lo), scale / 2 + 1e-8) << a;
    // The offset is a whole unit inside the data.
    const double offset = LeField<double>(b, 155 + 8 * a);
    EXPECT_EQ(offset, std::round(offset));
    EXPECT_GE(offset, coord(*in_lo) - 0.5);
    EXPECT_LE(offset, coord(*in_hi) + 0.5);
  }
  // First point record, decoded by hand.
  const uint8_t* p = &b[point_offset];
  const double x =
      LeField<int32_t>(b, point_offset) * LeField<double>(b, 131) + LeField<double>(b, 155);
  EXPECT_NEAR(x, points[0].x, 0.0005 + 1e-8);
  EXPECT_EQ(LeField<uint16_t>(b, point_offset + 30), points[0].r);
  EXPECT_EQ(p[14] & 0x0F, points[0].return_number);
  EXPECT_EQ(p[14] >> 4, points[0].number_of_returns);
  EXPECT_EQ(p[16], points[0].classification);
}

TEST_F(LasIoTest, WithoutCrsThereIsNoVlr) {
  const fs::path path = dir_ / "plain.las";
  WriteLas(path, RandomUtmPoints(7, 5), V14());
  const Bytes b = ReadBytes(path);
  EXPECT_EQ(LeField<uint32_t>(b, 100), 0u);
  EXPECT_EQ(LeField<uint32_t>(b, 96), 375u);
  EXPECT_EQ(b.size(), 375u + 7 * 36);
}

TEST_F(LasIoTest, EmptyCloudRoundTrips) {
  const fs::path path = dir_ / "empty.las";
  WriteLas(path, {}, V14());
  EXPECT_EQ(fs::file_size(path), 375u);
  EXPECT_TRUE(ReadLas(path).points.empty());
}

TEST_F(LasIoTest, ScaleCoarsensOnlyWhereTheExtentNeedsIt) {
  const fs::path path = dir_ / "wide.las";
  std::vector<PointRecord> points(2);
  points[0].x = 0;
  points[1].x = 1e7;  // 1e7 mm would overflow int32
  points[1].y = 1000;
  WriteLas(path, points, V14());
  const LasCloud cloud = ReadLas(path);
  EXPECT_EQ(cloud.scale[0], 0.01);
  EXPECT_EQ(cloud.scale[1], 0.001);
  EXPECT_NEAR(cloud.points[1].x, 1e7, 0.005);

  LasWriteOptions fine;
  fine.scale = 1e-4;
  try {
    WriteLas(path, points, fine);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("scale"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadLas(path).scale[0], 0.01) << "the old file must survive";
}

TEST_F(LasIoTest, GeographicCrsGetsAFineHorizontalScale) {
  const fs::path path = dir_ / "geo.las";
  std::vector<PointRecord> points(3);
  for (int i = 0; i < 3; ++i) {
    points[i].x = 9.1 + 0.001 * i;
    points[i].y = 48.7 + 0.002 * i;
    points[i].z = 300 + i;
  }
  LasWriteOptions options = V14();
  options.crs = "EPSG:4326";
  WriteLas(path, points, options);
  const LasCloud cloud = ReadLas(path);
  EXPECT_EQ(cloud.scale[0], 1e-7);
  EXPECT_EQ(cloud.scale[1], 1e-7);
  EXPECT_EQ(cloud.scale[2], 0.001);
  EXPECT_NEAR(cloud.points[2].y, 48.704, 1e-7);
}

TEST_F(LasIoTest, BadOptionsAreReported) {
  LasWriteOptions options = V14();
  options.scale = -1;
  EXPECT_FALSE(options.Check());
  EXPECT_NE(options.Problem().find("-1"), std::string::npos) << options.Problem();
  options.scale = 0;
  options.crs = "EPSG:999999999";
  EXPECT_FALSE(options.Check());
  EXPECT_NE(options.Problem().find("EPSG:999999999"), std::string::npos) << options.Problem();
  EXPECT_THROW(WriteLas(dir_ / "x.las", RandomUtmPoints(3, 1), options), Error);
  EXPECT_TRUE(DirIsEmpty());
}

TEST_F(LasIoTest, NonFiniteCoordinatesAreRefusedWithNoFileLeft) {
  const fs::path path = dir_ / "nan.las";
  std::vector<PointRecord> points = RandomUtmPoints(20, 2);
  points[13].z = std::numeric_limits<double>::quiet_NaN();
  try {
    WriteLas(path, points, V14());
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("point 13"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(DirIsEmpty());
  points[13].z = 300;
  points[4].x = std::numeric_limits<double>::infinity();
  EXPECT_THROW(WriteLas(path, points), Error);
  EXPECT_TRUE(DirIsEmpty());
}

// A LAS 1.2 file built byte by byte: header of 227 bytes, no VLRs, formats 0-3
// (with `extra` user bytes per record, which the reader must skip).
struct LegacyPoint {
  int32_t x, y, z;
  uint16_t intensity;
  uint8_t return_number, number_of_returns, class_byte;
  uint16_t r, g, b;
};

Bytes BuildLas12(int format, const std::vector<LegacyPoint>& points, int extra) {
  const size_t base[4] = {20, 28, 26, 34};
  const size_t record = base[format] + extra;
  Bytes b(227 + points.size() * record, 0);
  std::memcpy(b.data(), "LASF", 4);
  b[24] = 1;
  b[25] = 2;
  SetLeField<uint16_t>(&b, 94, 227);
  SetLeField<uint32_t>(&b, 96, 227);
  b[104] = static_cast<uint8_t>(format);
  SetLeField<uint16_t>(&b, 105, static_cast<uint16_t>(record));
  SetLeField<uint32_t>(&b, 107, static_cast<uint32_t>(points.size()));
  const double scale[3] = {0.01, 0.01, 0.001}, offset[3] = {431000, 5410000, 0};
  for (int a = 0; a < 3; ++a) {
    SetLeField<double>(&b, 131 + 8 * a, scale[a]);
    SetLeField<double>(&b, 155 + 8 * a, offset[a]);
  }
  for (size_t i = 0; i < points.size(); ++i) {
    const size_t at = 227 + i * record;
    const LegacyPoint& p = points[i];
    SetLeField<int32_t>(&b, at, p.x);
    SetLeField<int32_t>(&b, at + 4, p.y);
    SetLeField<int32_t>(&b, at + 8, p.z);
    SetLeField<uint16_t>(&b, at + 12, p.intensity);
    b[at + 14] = static_cast<uint8_t>(p.return_number | (p.number_of_returns << 3) | 0x40);
    b[at + 15] = p.class_byte;
    b[at + 16] = 0xF3;  // scan angle rank -13
    b[at + 17] = 0xAB;  // user data
    SetLeField<uint16_t>(&b, at + 18, 4242);
    if (format == 1 || format == 3) SetLeField<double>(&b, at + 20, 123456.789);
    const size_t rgb = format == 2 ? 20 : 28;
    if (format >= 2) {
      SetLeField<uint16_t>(&b, at + rgb, p.r);
      SetLeField<uint16_t>(&b, at + rgb + 2, p.g);
      SetLeField<uint16_t>(&b, at + rgb + 4, p.b);
    }
    for (int e = 0; e < extra; ++e) b[at + base[format] + e] = 0xEE;
  }
  return b;
}

TEST_F(LasIoTest, HandBuiltLas12Formats0To3AreRead) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int32_t> coord(-2000000, 2000000);
  std::uniform_int_distribution<int> u16(0, 65535), ret(1, 7), cls(0, 255);
  for (int format = 0; format <= 3; ++format) {
    for (const int n : {7, 93}) {
      SCOPED_TRACE("format " + std::to_string(format) + ", " + std::to_string(n) + " points");
      std::vector<LegacyPoint> points(n);
      for (LegacyPoint& p : points) {
        p = {coord(rng),
             coord(rng),
             coord(rng),
             static_cast<uint16_t>(u16(rng)),
             0,
             static_cast<uint8_t>(ret(rng)),
             static_cast<uint8_t>(cls(rng)),
             static_cast<uint16_t>(u16(rng)),
             static_cast<uint16_t>(u16(rng)),
             static_cast<uint16_t>(u16(rng))};
        p.return_number = static_cast<uint8_t>(1 + u16(rng) % p.number_of_returns);
      }
      const fs::path path =
          dir_ / ("f" + std::to_string(format) + "_" + std::to_string(n) + ".las");
      WriteBytes(path, BuildLas12(format, points, n == 93 ? 3 : 0));
      const LasCloud cloud = ReadLas(path);
      EXPECT_EQ(cloud.version_major, 1);
      EXPECT_EQ(cloud.version_minor, 2);
      EXPECT_EQ(cloud.point_format, format);
      EXPECT_EQ(cloud.has_rgb, format >= 2);
      ASSERT_EQ(cloud.points.size(), static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) {
        const LegacyPoint& p = points[i];
        const PointRecord& q = cloud.points[i];
        EXPECT_EQ(q.x, p.x * 0.01 + 431000) << i;
        EXPECT_EQ(q.y, p.y * 0.01 + 5410000) << i;
        EXPECT_EQ(q.z, p.z * 0.001) << i;
        EXPECT_EQ(q.intensity, p.intensity) << i;
        EXPECT_EQ(q.return_number, p.return_number) << i;
        EXPECT_EQ(q.number_of_returns, p.number_of_returns) << i;
        EXPECT_EQ(q.classification, p.class_byte & 0x1F) << i;
        EXPECT_EQ(q.r, format >= 2 ? p.r : 0) << i;
        EXPECT_EQ(q.g, format >= 2 ? p.g : 0) << i;
        EXPECT_EQ(q.b, format >= 2 ? p.b : 0) << i;
      }
    }
  }
}

TEST_F(LasIoTest, WktInAnEvlrIsRead) {
  const fs::path path = dir_ / "evlr.las";
  WriteLas(path, RandomUtmPoints(7, 9), V14());
  Bytes b = ReadBytes(path);
  OGRSpatialReference srs;
  ASSERT_EQ(srs.SetFromUserInput("EPSG:25833"), OGRERR_NONE);
  char* wkt = nullptr;
  ASSERT_EQ(srs.exportToWkt(&wkt), OGRERR_NONE);
  const std::string text = wkt;
  CPLFree(wkt);
  const size_t start = b.size();
  b.resize(start + 60 + text.size() + 1, 0);
  std::memcpy(&b[start + 2], "LASF_Projection", 15);
  SetLeField<uint16_t>(&b, start + 18, 2112);
  SetLeField<uint64_t>(&b, start + 20, text.size() + 1);
  std::memcpy(&b[start + 60], text.data(), text.size());
  SetLeField<uint64_t>(&b, 235, start);
  SetLeField<uint32_t>(&b, 243, 1);
  WriteBytes(path, b);
  const LasCloud cloud = ReadLas(path);
  EXPECT_EQ(cloud.points.size(), 7u);
  EXPECT_EQ(cloud.crs_wkt, text);
}

class LasMalformedTest : public LasIoTest {
 protected:
  // A valid file to break.
  Bytes Valid() {
    const fs::path path = dir_ / "valid.las";
    WriteLas(path, RandomUtmPoints(93, 4), V14());
    return ReadBytes(path);
  }
  fs::path Write(const Bytes& b) {
    const fs::path path = dir_ / "broken.las";
    WriteBytes(path, b);
    return path;
  }
};

TEST_F(LasMalformedTest, WrongSignature) {
  Bytes b = Valid();
  std::memcpy(b.data(), "LASX", 4);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "expected the signature 'LASF'");
  const fs::path text = dir_ / "text.las";
  std::ofstream(text) << "1 2 3\n";
  ExpectInputError([&] { ReadLas(text); }, text, "not a LAS file");
}

TEST_F(LasMalformedTest, TruncatedHeader) {
  Bytes b = Valid();
  b.resize(200);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "truncated header");
}

TEST_F(LasMalformedTest, HeaderSizeTooSmall) {
  Bytes b = Valid();
  SetLeField<uint16_t>(&b, 94, 227);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "expected at least 375");
}

TEST_F(LasMalformedTest, TruncatedPoints) {
  Bytes b = Valid();
  b.resize(b.size() - 10);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "truncated point data");
}

TEST_F(LasMalformedTest, PointCountBeyondFileSize) {
  Bytes b = Valid();
  SetLeField<uint64_t>(&b, 247, uint64_t{1} << 60);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "room for 93");
}

TEST_F(LasMalformedTest, LazCompressedBit) {
  Bytes b = Valid();
  b[104] |= 0x80;
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "LAZ-compressed");
}

TEST_F(LasMalformedTest, UnknownPointFormat) {
  Bytes b = Valid();
  b[104] = 11;
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "unknown point data format 11 (expected 0-10)");
}

TEST_F(LasMalformedTest, RecordTooShortForItsFormat) {
  Bytes b = Valid();
  SetLeField<uint16_t>(&b, 105, 30);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "too short for format 7");
}

TEST_F(LasMalformedTest, UnsupportedVersion) {
  Bytes b = Valid();
  b[25] = 7;
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "expected 1.0-1.4");
}

TEST_F(LasMalformedTest, VlrRunningIntoThePoints) {
  LasWriteOptions options = V14();
  options.crs = "EPSG:32632";
  const fs::path valid = dir_ / "crs.las";
  WriteLas(valid, RandomUtmPoints(3, 4), options);
  Bytes b = ReadBytes(valid);
  SetLeField<uint16_t>(&b, 375 + 20, 60000);
  const fs::path path = Write(b);
  ExpectInputError([&] { ReadLas(path); }, path, "variable length record 1 of 1");
}

TEST_F(LasMalformedTest, MissingFileNamesThePath) {
  const fs::path path = dir_ / "missing.las";
  try {
    ReadLas(path);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

// LAS 1.2 and 1.4 with Extra Bytes: written by WriteLas, read back by ReadLas,
// and the bytes checked against LAS 1.4 R15 (the Extra Bytes VLR, LASF_Spec/4,
// one 192-byte descriptor per field).
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "sapmvs/io/las_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

class LasExtraBytesTest : public test::ScratchTest {};

template <typename T>
T LeValue(const Bytes& b, size_t at) {
  T v{};
  EXPECT_LE(at + sizeof(T), b.size());
  if (at + sizeof(T) <= b.size()) std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}

Bytes FileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<PointRecord> Points(int n) {
  std::vector<PointRecord> points(n);
  for (int i = 0; i < n; ++i) {
    points[i].x = 500000.25 + i;
    points[i].y = 5400000.5 - 2 * i;
    points[i].z = 300 + 0.125 * i;
    points[i].r = static_cast<uint16_t>(257 * i);
    points[i].classification = static_cast<uint8_t>(i % 32);
    points[i].return_number = 1;
    points[i].number_of_returns = static_cast<uint8_t>(1 + i % 7);
  }
  return points;
}

// One field of every type, with values at the ends of its range.
std::vector<LasExtraField> EveryType() {
  return {
      {"u8", "unsigned char", LasExtraType::kUint8, {0, 255, 7}},
      {"i8", "", LasExtraType::kInt8, {-128, 127, -1}},
      {"u16", "", LasExtraType::kUint16, {0, 65535, 3}},
      {"i16", "", LasExtraType::kInt16, {-32768, 32767, 0}},
      {"u32", "", LasExtraType::kUint32, {0, 4294967295.0, 12}},
      {"i32", "", LasExtraType::kInt32, {-2147483648.0, 2147483647.0, -5}},
      {"u64", "", LasExtraType::kUint64, {0, 9007199254740992.0, 1}},
      {"i64", "", LasExtraType::kInt64, {-9007199254740992.0, 9007199254740992.0, -1}},
      {"f32", "a float", LasExtraType::kFloat32, {0.25, -1.5, 1e-3f}},
      {"a name of exactly thirty-two ch.", "f64", LasExtraType::kFloat64, {0.1, -1e300, 3}},
  };
}

class LasVersionsTest : public LasExtraBytesTest,
                        public ::testing::WithParamInterface<LasVersion> {};

TEST_P(LasVersionsTest, EveryExtraTypeRoundTrips) {
  const fs::path path = dir_ / "extra.las";
  LasWriteOptions options;
  options.version = GetParam();
  options.crs = "EPSG:32632";
  const std::vector<LasExtraField> fields = EveryType();
  WriteLas(path, Points(3), options, fields);

  const LasCloud cloud = ReadLas(path, true);
  EXPECT_EQ(cloud.version_minor, GetParam() == LasVersion::k12 ? 2 : 4);
  EXPECT_EQ(cloud.point_format, GetParam() == LasVersion::k12 ? 2 : 7);
  EXPECT_FALSE(cloud.crs_wkt.empty());
  ASSERT_EQ(cloud.points.size(), 3u);
  EXPECT_NEAR(cloud.points[2].z, 300.25, 1e-9);
  EXPECT_EQ(cloud.points[2].r, 514);
  EXPECT_EQ(cloud.points[2].classification, 2);
  EXPECT_EQ(cloud.points[2].number_of_returns, 3);
  ASSERT_EQ(cloud.extras.size(), fields.size());
  for (size_t k = 0; k < fields.size(); ++k) {
    SCOPED_TRACE(fields[k].name);
    EXPECT_EQ(cloud.extras[k].name, fields[k].name);
    EXPECT_EQ(cloud.extras[k].description, fields[k].description);
    EXPECT_EQ(cloud.extras[k].type, fields[k].type);
    ASSERT_EQ(cloud.extras[k].values.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      const double expected = fields[k].type == LasExtraType::kFloat32
                                  ? static_cast<float>(fields[k].values[i])
                                  : fields[k].values[i];
      EXPECT_EQ(cloud.extras[k].values[i], expected) << i;
    }
  }
  // Without values asked for, the fields are listed but not read.
  const LasCloud names_only = ReadLas(path);
  ASSERT_EQ(names_only.extras.size(), fields.size());
  EXPECT_TRUE(names_only.extras[0].values.empty());
}

TEST_P(LasVersionsTest, ExtraBytesVlrFollowsTheSpecification) {
  const fs::path path = dir_ / "vlr.las";
  LasWriteOptions options;
  options.version = GetParam();
  const bool v12 = GetParam() == LasVersion::k12;
  const std::vector<LasExtraField> fields = {
      {"score", "photo-consistency", LasExtraType::kFloat32, {0.5, 0.75, -0.25}},
      {"views", "", LasExtraType::kUint16, {3, 4, 300}}};
  WriteLas(path, Points(3), options, fields);
  const Bytes b = FileBytes(path);
  const size_t header = v12 ? 227 : 375;
  EXPECT_EQ(b[24], 1);
  EXPECT_EQ(b[25], v12 ? 2 : 4);
  EXPECT_EQ(LeValue<uint16_t>(b, 94), header);
  EXPECT_EQ(b[104], v12 ? 2 : 7);
  const size_t base = v12 ? 26 : 36;
  EXPECT_EQ(LeValue<uint16_t>(b, 105), base + 4 + 2);  // record length
  // LAS 1.2 keeps the count in the legacy field, LAS 1.4 (format 7) in the
  // 64-bit one.
  EXPECT_EQ(LeValue<uint32_t>(b, 107), v12 ? 3u : 0u);
  if (!v12) {
    EXPECT_EQ(LeValue<uint64_t>(b, 247), 3u);
  }

  // No CRS: the only VLR is the Extra Bytes one.
  ASSERT_EQ(LeValue<uint32_t>(b, 100), 1u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[header + 2])), "LASF_Spec");
  EXPECT_EQ(LeValue<uint16_t>(b, header + 18), 4);
  ASSERT_EQ(LeValue<uint16_t>(b, header + 20), 2 * 192);
  const size_t d0 = header + 54, d1 = d0 + 192;
  EXPECT_EQ(LeValue<uint32_t>(b, 96), d1 + 192);  // offset to point data
  EXPECT_EQ(b[d0 + 2], 9);                        // float
  EXPECT_EQ(b[d0 + 3], 0b110);                    // min and max given
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[d0 + 4])), "score");
  EXPECT_EQ(LeValue<double>(b, d0 + 64), -0.25);
  EXPECT_EQ(LeValue<double>(b, d0 + 88), 0.75);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[d0 + 160])), "photo-consistency");
  EXPECT_EQ(b[d1 + 2], 3);  // unsigned short
  EXPECT_EQ(b[d1 + 3], 0);  // integer fields: no min or max
  EXPECT_EQ(LeValue<double>(b, d1 + 64), 0.0);
  // The third point's extra bytes, after its format's own.
  const size_t third = d1 + 192 + 2 * (base + 6);
  EXPECT_EQ(LeValue<float>(b, third + base), -0.25f);
  EXPECT_EQ(LeValue<uint16_t>(b, third + base + 4), 300);
  EXPECT_EQ(b.size(), third + base + 6);
}

INSTANTIATE_TEST_SUITE_P(BothVersions, LasVersionsTest,
                         ::testing::Values(LasVersion::k12, LasVersion::k14), [](const auto& p) {
                           return p.param == LasVersion::k12 ? "Las12" : "Las14";
                         });

TEST_F(LasExtraBytesTest, Las12StoresAnEpsgCrsAsGeoTiffKeysAndWkt) {
  const fs::path path = dir_ / "crs.las";
  LasWriteOptions options;
  options.crs = "EPSG:32632";
  WriteLas(path, Points(2), options);
  const Bytes b = FileBytes(path);
  ASSERT_EQ(LeValue<uint32_t>(b, 100), 2u);
  EXPECT_EQ(LeValue<uint16_t>(b, 6), 0) << "no WKT bit before LAS 1.4";
  // The GeoKeyDirectory: {1, 1, 0, keys}, then {id, 0, 1, value} by id.
  const size_t v = 227;
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[v + 2])), "LASF_Projection");
  EXPECT_EQ(LeValue<uint16_t>(b, v + 18), 34735);
  const size_t keys = v + 54;
  ASSERT_EQ(LeValue<uint16_t>(b, keys + 6), 3);
  EXPECT_EQ(LeValue<uint16_t>(b, keys + 8), 1024);   // GTModelType
  EXPECT_EQ(LeValue<uint16_t>(b, keys + 8 + 6), 1);  // projected
  EXPECT_EQ(LeValue<uint16_t>(b, keys + 24), 3072);  // ProjectedCSType
  EXPECT_EQ(LeValue<uint16_t>(b, keys + 24 + 6), 32632);
  EXPECT_NE(ReadLas(path).crs_wkt.find("32632"), std::string::npos);
}

TEST_F(LasExtraBytesTest, Las12RefusesWhatOnlyLas14Holds) {
  const fs::path path = dir_ / "x.las";
  std::vector<PointRecord> points = Points(3);
  points[1].classification = 32;
  try {
    WriteLas(path, points);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 1 has class 32"), std::string::npos) << e.what();
  }
  points[1].classification = 2;
  points[2].number_of_returns = 8;
  EXPECT_THROW(WriteLas(path, points), Error);
  EXPECT_TRUE(DirIsEmpty());
  LasWriteOptions v14;
  v14.version = LasVersion::k14;
  points[1].classification = 32;
  WriteLas(path, points, v14);
  EXPECT_EQ(ReadLas(path).points[1].classification, 32);
}

TEST_F(LasExtraBytesTest, BadFieldsAreRefusedBeforeAnythingIsWritten) {
  const fs::path path = dir_ / "bad.las";
  struct Case {
    LasExtraField field;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"views", "", LasExtraType::kUint16, {1, 2.5, 3}}, "point 1: value 2.5"},
      {{"views", "", LasExtraType::kUint16, {1, 65536, 3}}, "point 1: value 65536"},
      {{"n", "", LasExtraType::kFloat32, {0, 1e39, 0}}, "point 1: value"},
      {{"n", "", LasExtraType::kFloat64, {0, 0, std::nan("")}}, "point 2: value nan"},
      {{"", "", LasExtraType::kFloat32, {0, 0, 0}}, "expected a name of 1-32 characters"},
      {{std::string(33, 'a'), "", LasExtraType::kFloat32, {0, 0, 0}}, "1-32 characters"},
      {{"d", std::string(33, 'a'), LasExtraType::kFloat32, {0, 0, 0}}, "at most 32 characters"},
      {{"short", "", LasExtraType::kFloat32, {0, 0}}, "has 2 values for 3 points"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.expect);
    try {
      WriteLas(path, Points(3), {}, {c.field});
      ADD_FAILURE() << "expected sapmvs::Error";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": ", 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
    }
  }
  const LasExtraField a{"same", "", LasExtraType::kUint8, {0, 0, 0}};
  EXPECT_THROW(WriteLas(path, Points(3), {}, {a, a}), Error);
  EXPECT_TRUE(DirIsEmpty());
}

TEST_F(LasExtraBytesTest, AVlrDescribingMoreBytesThanTheRecordsHoldIsIgnored) {
  const fs::path path = dir_ / "mismatch.las";
  WriteLas(path, Points(3), {}, {{"f", "", LasExtraType::kFloat32, {1, 2, 3}}});
  Bytes b = FileBytes(path);
  b[227 + 54 + 2] = 10;  // float -> double: 8 bytes described, 4 there
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
  const LasCloud cloud = ReadLas(path, true);
  EXPECT_TRUE(cloud.extras.empty());
  ASSERT_EQ(cloud.points.size(), 3u);
  EXPECT_NEAR(cloud.points[2].x, 500002.25, 1e-9);
}

TEST_F(LasExtraBytesTest, VersionsParseFromTheirNames) {
  EXPECT_EQ(ParseLasVersion("1.2"), LasVersion::k12);
  EXPECT_EQ(ParseLasVersion("1.4"), LasVersion::k14);
  EXPECT_EQ(ToString(LasVersion::k14), "1.4");
  try {
    ParseLasVersion("1.3");
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'1.3' (--las-version): expected 1.2 or 1.4"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

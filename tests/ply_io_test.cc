#include "sapmvs/io/ply_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "sapmvs/util/error.h"
#include "sapmvs/util/memory_use.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

class PlyIoTest : public test::ScratchTest {};

Bytes ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteBytes(const fs::path& path, const Bytes& b) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(b.data()), b.size());
}

void WritePlyText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Big-endian encoding written here, independently of ply_io.cc.
template <typename T>
void PutBigEndian(Bytes* b, T v) {
  uint8_t raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T); ++i) b->push_back(raw[sizeof(T) - 1 - i]);
}

// Points around a UTM site: X ~ 5e5, Y ~ 5.4e6, with every optional field.
PointCloud RandomCloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-1500, 1500), unit(-1, 1);
  std::uniform_int_distribution<int> byte(0, 255), views(2, 12);
  PointCloud c;
  c.has_normals = c.has_colors = c.has_scores = c.has_views = true;
  for (int i = 0; i < n; ++i) {
    CloudPoint p;
    p.position = {5e5 + d(rng), 5.4e6 + d(rng), 300 + d(rng) / 30};
    p.normal = Eigen::Vector3f(unit(rng), unit(rng), 1).normalized();
    p.color = {static_cast<uint8_t>(byte(rng)), static_cast<uint8_t>(byte(rng)),
               static_cast<uint8_t>(byte(rng))};
    p.score = static_cast<float>(unit(rng));
    p.num_views = views(rng);
    c.points.push_back(p);
  }
  return c;
}

void ExpectSamePoints(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    const CloudPoint &p = a.points[i], &q = b.points[i];
    EXPECT_EQ(p.position, q.position) << i;  // bit-exact: stored as double
    if (a.has_normals) {
      EXPECT_EQ(p.normal, q.normal) << i;
    }
    if (a.has_colors) {
      EXPECT_EQ(p.color, q.color) << i;
    }
    if (a.has_scores) {
      EXPECT_EQ(p.score, q.score) << i;
    }
    if (a.has_views) {
      EXPECT_EQ(p.num_views, q.num_views) << i;
    }
  }
}

TEST_F(PlyIoTest, BinaryRoundTripKeepsEveryFieldAndTheCrs) {
  PointCloud cloud = RandomCloud(1000, 7);
  cloud.crs = "PROJCS[\"WGS 84 / UTM zone 32N\",\n  GEOGCS[\"WGS 84\"]]";
  const fs::path path = dir_ / "cloud.ply";
  WritePly(path, cloud);
  const PointCloud back = ReadPly(path);
  EXPECT_TRUE(back.has_normals && back.has_colors && back.has_scores && back.has_views);
  EXPECT_EQ(back.crs, "PROJCS[\"WGS 84 / UTM zone 32N\",   GEOGCS[\"WGS 84\"]]");
  ExpectSamePoints(cloud, back);
}

// A filtered read keeps the points the filter accepts, in file order, with
// the file's flags and CRS, and shows the filter every point once, binary
// and ascii alike.
TEST_F(PlyIoTest, FilteredReadKeepsTheAcceptedPointsInOrder) {
  PointCloud cloud = RandomCloud(777, 11);
  cloud.crs = "EPSG:32632";
  const fs::path path = dir_ / "cloud.ply";
  WritePly(path, cloud);
  auto west = [](const Eigen::Vector3d& p) { return p.x() < 5e5; };
  PointCloud expected = cloud;
  expected.points.clear();
  std::copy_if(cloud.points.begin(), cloud.points.end(), std::back_inserter(expected.points),
               [&](const CloudPoint& p) { return west(p.position); });
  ASSERT_GT(expected.points.size(), 100u);
  ASSERT_LT(expected.points.size(), cloud.points.size() - 100);
  long shown = 0;
  const PointCloud back = ReadPly(path, [&](const Eigen::Vector3d& p) {
    ++shown;
    return west(p);
  });
  EXPECT_EQ(shown, 777);
  // Reserved for every point of the header where unwritten pages cost
  // nothing, so that the points are not copied as they come.
  if (UnwrittenMemoryIsFree()) {
    EXPECT_GE(back.points.capacity(), 777u);
  }
  EXPECT_EQ(back.crs, "EPSG:32632");
  EXPECT_TRUE(back.has_normals && back.has_colors && back.has_scores && back.has_views);
  ExpectSamePoints(expected, back);

  const fs::path ascii = dir_ / "hand.ply";
  WritePlyText(ascii,
               "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
               "property float z\nend_header\n-1 0 0\n6e5 0 0\n-3 0 0\n7e5 0 0\n");
  const PointCloud a = ReadPly(ascii, west);
  ASSERT_EQ(a.points.size(), 2u);
  EXPECT_EQ(a.points[0].position.x(), -1);
  EXPECT_EQ(a.points[1].position.x(), -3);
  EXPECT_EQ(ReadPly(ascii, PointFilter()).points.size(), 4u);
}

TEST_F(PlyIoTest, WrittenBytesFollowTheSpecification) {
  PointCloud cloud = RandomCloud(3, 11);
  cloud.has_normals = cloud.has_scores = false;
  const fs::path path = dir_ / "cloud.ply";
  WritePly(path, cloud);
  const Bytes b = ReadBytes(path);
  const std::string text(b.begin(), b.end());
  const size_t end = text.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = text.substr(0, end);
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u) << header;
  EXPECT_NE(header.find("element vertex 3\nproperty double x\nproperty double y\n"
                        "property double z\nproperty uchar red\nproperty uchar green\n"
                        "property uchar blue\nproperty uchar scalar_views\n"),
            std::string::npos)
      << header;
  // x y z (3 doubles) + RGB + views = 28 bytes per vertex.
  const size_t data = end + std::strlen("end_header\n");
  ASSERT_EQ(b.size() - data, 3u * 28u);
  double y1;
  std::memcpy(&y1, b.data() + data + 28 + 8, 8);
  EXPECT_EQ(y1, cloud.points[1].position.y());
  EXPECT_EQ(b[data + 2 * 28 + 24 + 1], cloud.points[2].color[1]);
  EXPECT_EQ(b[data + 2 * 28 + 27], cloud.points[2].num_views);
}

TEST_F(PlyIoTest, ViewCountsAbove255AreWrittenAsInt) {
  PointCloud cloud = RandomCloud(5, 3);
  cloud.points[4].num_views = 1000;
  const fs::path path = dir_ / "cloud.ply";
  WritePly(path, cloud);
  const Bytes b = ReadBytes(path);
  EXPECT_NE(std::string(b.begin(), b.end()).find("property int scalar_views\n"), std::string::npos);
  EXPECT_EQ(ReadPly(path).points[4].num_views, 1000);
}

TEST_F(PlyIoTest, OddCountsRoundTrip) {
  // 65537 crosses the writer's 65536-point chunk and the reader's buffer.
  for (int n : {0, 1, 7, 65537}) {
    PointCloud cloud = RandomCloud(n, 100 + n);
    cloud.has_normals = false;
    const fs::path path = dir_ / ("n" + std::to_string(n) + ".ply");
    WritePly(path, cloud);
    const PointCloud back = ReadPly(path);
    EXPECT_FALSE(back.has_normals);
    ExpectSamePoints(cloud, back);
  }
}

TEST_F(PlyIoTest, OnlyCoordinatesWhenNoOptionalField) {
  PointCloud cloud;
  cloud.points.resize(2);
  cloud.points[1].position = {1.5, -2.25, 1e-3};
  const fs::path path = dir_ / "xyz.ply";
  WritePly(path, cloud);
  const Bytes b = ReadBytes(path);
  const size_t data = std::string(b.begin(), b.end()).find("end_header\n") + 11;
  EXPECT_EQ(b.size() - data, 2u * 24u);
  const PointCloud back = ReadPly(path);
  EXPECT_FALSE(back.has_normals || back.has_colors || back.has_scores || back.has_views);
  EXPECT_TRUE(back.crs.empty());
  ExpectSamePoints(cloud, back);
}

TEST_F(PlyIoTest, ReadsAsciiBuiltByHand) {
  const fs::path path = dir_ / "hand.ply";
  WritePlyText(path,
               "ply\r\n"
               "format ascii 1.0\r\n"
               "comment made by hand\r\n"
               "comment crs EPSG:32632\r\n"
               "obj_info anything\r\n"
               "element vertex 3\r\n"
               "property float x\r\n"
               "property float y\r\n"
               "property double z\r\n"
               "property int extra\r\n"
               "property list uchar int indices\r\n"
               "property uchar red\r\n"
               "property uchar green\r\n"
               "property uchar blue\r\n"
               "property float nx\r\n"
               "property float ny\r\n"
               "property float nz\r\n"
               "element face 1\r\n"
               "property list uchar int vertex_indices\r\n"
               "end_header\r\n"
               "1.5 2 300.25 -7 2 10 11 255 0 128 0 0 1\r\n"
               "-1 -2.5e1 0 3 0 1 2 3 0.6 0 0.8\r\n"
               "\r\n"
               "4 5 6 0 1 9 7 8 9 0 1 0\r\n"
               "3 0 1 2\r\n");
  const PointCloud c = ReadPly(path);
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.crs, "EPSG:32632");
  EXPECT_TRUE(c.has_colors && c.has_normals);
  EXPECT_FALSE(c.has_scores || c.has_views);
  EXPECT_EQ(c.points[0].position, Eigen::Vector3d(1.5, 2, 300.25));
  EXPECT_EQ(c.points[1].position, Eigen::Vector3d(-1, -25, 0));
  EXPECT_EQ(c.points[2].position, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(c.points[0].color, (std::array<uint8_t, 3>{255, 0, 128}));
  EXPECT_EQ(c.points[1].color, (std::array<uint8_t, 3>{1, 2, 3}));
  EXPECT_EQ(c.points[1].normal, Eigen::Vector3f(0.6f, 0, 0.8f));
  EXPECT_EQ(c.points[2].normal, Eigen::Vector3f(0, 1, 0));
}

TEST_F(PlyIoTest, ReadsBigEndianBuiltByHand) {
  // An element before the vertices (skipped), a list inside the vertex
  // element, ushort colour and an int view count.
  const std::string header =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "element camera 2\n"
      "property float k\n"
      "property list uchar short ids\n"
      "element vertex 2\n"
      "property double x\n"
      "property double y\n"
      "property float z\n"
      "property list uint8 int32 idx\n"
      "property ushort red\n"
      "property ushort green\n"
      "property ushort blue\n"
      "property float score\n"
      "property int views\n"
      "end_header\n";
  Bytes b(header.begin(), header.end());
  PutBigEndian<float>(&b, 1.f);
  b.push_back(2);
  PutBigEndian<int16_t>(&b, 5);
  PutBigEndian<int16_t>(&b, 6);
  PutBigEndian<float>(&b, 2.f);
  b.push_back(0);
  const double xs[2] = {512345.678901, 498765.4321}, ys[2] = {5412345.123456, 5398765.5};
  for (int i = 0; i < 2; ++i) {
    PutBigEndian<double>(&b, xs[i]);
    PutBigEndian<double>(&b, ys[i]);
    PutBigEndian<float>(&b, 250.5f + i);
    b.push_back(static_cast<uint8_t>(i + 1));
    for (int k = 0; k <= i; ++k) PutBigEndian<int32_t>(&b, 99);
    PutBigEndian<uint16_t>(&b, 65535);
    PutBigEndian<uint16_t>(&b, 0);
    PutBigEndian<uint16_t>(&b, static_cast<uint16_t>(100 * 257));
    PutBigEndian<float>(&b, 0.75f - i);
    PutBigEndian<int32_t>(&b, 3 + i);
  }
  const fs::path path = dir_ / "be.ply";
  WriteBytes(path, b);
  const PointCloud c = ReadPly(path);
  ASSERT_EQ(c.points.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(c.points[i].position, Eigen::Vector3d(xs[i], ys[i], 250.5 + i));
    EXPECT_EQ(c.points[i].color, (std::array<uint8_t, 3>{255, 0, 100}));
    EXPECT_EQ(c.points[i].score, 0.75f - i);
    EXPECT_EQ(c.points[i].num_views, 3 + i);
  }
  EXPECT_TRUE(c.has_colors && c.has_scores && c.has_views);
}

// As CloudCompare writes its scalar fields (float, `scalar_` names) and as
// sapmvs writes them; the big-endian test above reads the plain names.
TEST_F(PlyIoTest, ScalarPrefixedScoreAndViewsAreRead) {
  const fs::path path = dir_ / "cc.ply";
  WritePlyText(path,
               "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
               "property double z\nproperty float scalar_score\nproperty float scalar_views\n"
               "end_header\n1 2 3 0.5 4\n4 5 6 -0.25 7\n");
  const PointCloud c = ReadPly(path);
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_TRUE(c.has_scores && c.has_views);
  EXPECT_EQ(c.points[1].score, -0.25f);
  EXPECT_EQ(c.points[1].num_views, 7);
  // And what the writer declares.
  PointCloud w = RandomCloud(2, 5);
  WritePly(path, w);
  const Bytes b = ReadBytes(path);
  const std::string text(b.begin(), b.end());
  EXPECT_NE(text.find("property float scalar_score\nproperty uchar scalar_views\n"),
            std::string::npos);
  EXPECT_EQ(text.find(" score\n"), std::string::npos);
}

TEST_F(PlyIoTest, MalformedHeadersNameTheLine) {
  const std::vector<test::MalformedText> cases = {
      {"not ply", "PLY\nformat ascii 1.0\nend_header\n", 1, "expected 'ply'"},
      {"unknown format", "ply\nformat binary_middle_endian 1.0\nend_header\n", 2, "unknown format"},
      {"bad version", "ply\nformat ascii 2.0\nend_header\n", 2, "version 1.0"},
      {"property first", "ply\nformat ascii 1.0\nproperty float x\nend_header\n", 3,
       "before any 'element'"},
      {"unknown type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
       4, "unknown property type"},
      {"negative count", "ply\nformat ascii 1.0\nelement vertex -5\nend_header\n", 3,
       "non-negative element count"},
      {"unknown keyword", "ply\nformat ascii 1.0\nvertices 3\nend_header\n", 3,
       "unexpected header keyword"},
      {"no end", "ply\nformat ascii 1.0\nelement vertex 0\n", 3, "without 'end_header'"},
      {"float list count",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int i\nend_header\n", 4,
       "integer type"},
      {"no format", "ply\nelement vertex 0\nend_header\n", 2, "'format' line"},
      {"no vertex", "ply\nformat ascii 1.0\nelement face 0\nend_header\n", 0, "no 'vertex'"},
      {"no z",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "end_header\n1 2\n",
       0, "x, y, z"},
      {"empty", "", 0, "empty file"},
  };
  for (const auto& m : cases) {
    SCOPED_TRACE(m.name);
    const fs::path path = dir_ / "bad.ply";
    WritePlyText(path, m.text);
    test::ExpectInputError([&] { ReadPly(path); }, "bad.ply", m.line, m.expect);
  }
}

TEST_F(PlyIoTest, MalformedAsciiDataNamesTheLine) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n";
  const std::vector<test::MalformedText> cases = {
      {"too few values", header + "1 2 3\n4 5\n", 9, "too few values for vertex 1"},
      {"too many values", header + "1 2 3 4\n4 5 6\n", 8, "expected 3 values"},
      {"not a number", header + "1 2 3\n4 five 6\n", 9, "got 'five'"},
      {"nan", header + "1 2 3\nnan 5 6\n", 9, "non-finite coordinate in vertex 1"},
      {"truncated", header + "1 2 3\n", 8, "truncated: expected 2 vertex lines"},
  };
  for (const auto& m : cases) {
    SCOPED_TRACE(m.name);
    const fs::path path = dir_ / "bad.ply";
    WritePlyText(path, m.text);
    test::ExpectInputError([&] { ReadPly(path); }, "bad.ply", m.line, m.expect);
  }
}

TEST_F(PlyIoTest, TruncatedBinaryNamesTheVertex) {
  const PointCloud cloud = RandomCloud(10, 5);
  const fs::path path = dir_ / "cut.ply";
  WritePly(path, cloud);
  Bytes b = ReadBytes(path);
  // The record is 24 + 12 + 3 + 4 + 1 = 44 bytes; cut inside vertex 7's z.
  const size_t data = std::string(b.begin(), b.end()).find("end_header\n") + 11;
  ASSERT_EQ(b.size() - data, 10u * 44u);
  b.resize(data + 7 * 44 + 20);
  WriteBytes(path, b);
  test::ExpectInputError([&] { ReadPly(path); }, "cut.ply", 0,
                         "truncated: the data ends in vertex 7 of 10 (0-based), property 'z'");
}

TEST_F(PlyIoTest, NonFiniteBinaryCoordinateIsRefused) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  Bytes b(header.begin(), header.end());
  const float v[6] = {1, 2, 3, 4, std::numeric_limits<float>::quiet_NaN(), 6};
  const uint8_t* raw = reinterpret_cast<const uint8_t*>(v);
  b.insert(b.end(), raw, raw + sizeof v);
  const fs::path path = dir_ / "nan.ply";
  WriteBytes(path, b);
  test::ExpectInputError([&] { ReadPly(path); }, "nan.ply", 0, "non-finite coordinate in vertex 1");
}

// Casting NaN, 3e38, -1 or 2.5 to an int count would be undefined behaviour
// or a wrong count; the binary path must refuse them as the ASCII one does
// (docs/bad-inputs.md, PlyViews*).
TEST_F(PlyIoTest, BinaryViewsThatAreNoCountAreRefused) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nproperty float views\nend_header\n";
  for (const float views : {std::numeric_limits<float>::quiet_NaN(), 3e38f, -1.0f, 2.5f}) {
    Bytes b(header.begin(), header.end());
    const float v[8] = {1, 2, 3, 4, 4, 5, 6, views};
    const uint8_t* raw = reinterpret_cast<const uint8_t*>(v);
    b.insert(b.end(), raw, raw + sizeof v);
    const fs::path path = dir_ / "views.ply";
    WriteBytes(path, b);
    test::ExpectInputError([&] { ReadPly(path); }, "views.ply", 0,
                           "vertex 1 of 2 (0-based): views = ");
  }
}

// A filtered read of fixed-size binary points reads no more than the
// position of a point the filter drops (the tiled merge reads each group's
// cloud once per tile): a bad count there goes unread, and is refused where
// the point is kept.
TEST_F(PlyIoTest, FilteredBinaryReadSkipsTheRestOfDroppedPoints) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nproperty float views\nend_header\n";
  Bytes b(header.begin(), header.end());
  const float v[8] = {1, 2, 3, 4, 10, 5, 6, -1.0f};
  const uint8_t* raw = reinterpret_cast<const uint8_t*>(v);
  b.insert(b.end(), raw, raw + sizeof v);
  const fs::path path = dir_ / "views.ply";
  WriteBytes(path, b);
  const PointCloud near = ReadPly(path, [](const Eigen::Vector3d& p) { return p.x() < 5; });
  ASSERT_EQ(near.points.size(), 1u);
  EXPECT_EQ(near.points[0].num_views, 4);
  test::ExpectInputError([&] { ReadPly(path, [](const Eigen::Vector3d&) { return true; }); },
                         "views.ply", 0, "vertex 1 of 2 (0-based): views = ");
}

// Found by fuzz_ply: a float colour of NaN passed std::clamp unchanged and
// its cast to 8 bits was undefined (UBSan fails this in the sanitizer build).
TEST_F(PlyIoTest, NanFloatColourReadsAsBlack) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nproperty float red\nproperty float green\n"
      "property float blue\nend_header\n";
  Bytes b(header.begin(), header.end());
  const float v[6] = {1, 2, 3, std::numeric_limits<float>::quiet_NaN(), 300, 7.4f};
  const uint8_t* raw = reinterpret_cast<const uint8_t*>(v);
  b.insert(b.end(), raw, raw + sizeof v);
  const fs::path path = dir_ / "nan_colour.ply";
  WriteBytes(path, b);
  const PointCloud c = ReadPly(path);
  ASSERT_EQ(c.points.size(), 1u);
  ASSERT_TRUE(c.has_colors);
  EXPECT_EQ(c.points[0].color[0], 0);
  EXPECT_EQ(c.points[0].color[1], 255);
  EXPECT_EQ(c.points[0].color[2], 7);
}

TEST_F(PlyIoTest, FifoIsRefusedWithoutBlocking) {
  const fs::path path = dir_ / "fifo.ply";
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  test::ExpectInputError([&] { ReadPly(path); }, "fifo.ply", 0, "cannot open file (a FIFO");
}

TEST_F(PlyIoTest, MissingFileIsAnInputError) {
  test::ExpectInputError([&] { ReadPly(dir_ / "missing.ply"); }, "missing.ply", 0,
                         "cannot open file");
}

TEST_F(PlyIoTest, WriterRefusesNonFiniteCoordinatesAndLeavesNothing) {
  PointCloud cloud = RandomCloud(4, 9);
  cloud.points[2].position.z() = std::numeric_limits<double>::infinity();
  try {
    WritePly(dir_ / "bad.ply", cloud);
    ADD_FAILURE() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 2 has a non-finite coordinate"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(DirIsEmpty());
}

TEST_F(PlyIoTest, WriterRefusesNegativeViewCounts) {
  PointCloud cloud = RandomCloud(2, 9);
  cloud.points[1].num_views = -1;
  EXPECT_THROW(WritePly(dir_ / "bad.ply", cloud), Error);
  EXPECT_TRUE(DirIsEmpty());
}

}  // namespace
}  // namespace sapmvs

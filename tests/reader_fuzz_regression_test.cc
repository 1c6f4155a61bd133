// Inputs that scripts/fuzz.sh found to crash a reader, or to make it throw
// something other than sapmvs::Error, or to run into undefined behaviour
// (caught when this test runs in the sanitizer build, scripts/test.sh
// --sanitize). Each must now fail, or read, in sapmvs's own terms.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>

#include "sapmvs/block/block_reader.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// Runs `fn`, which must throw InputError (not another exception) naming
// `file_name`.
template <typename Fn>
void ExpectInputErrorFor(Fn&& fn, const std::string& file_name, const std::string& text = "") {
  try {
    fn();
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(fs::path(e.file()).filename().string(), file_name) << e.what();
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

BlockReadOptions NoSizeCheck(BlockFormat format) {
  BlockReadOptions o;
  o.format = format;
  o.check_image_sizes = false;
  return o;
}

// yaml-cpp throws its own exception when a scalar is subscripted.
TEST(ReaderFuzzRegression, YamlScalarWhereAMappingIsExpected) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  std::ofstream(dir / "orientation.txt") << "a 0 0 10 0 0 0\n";
  std::ofstream(dir / "images" / "a.jpg") << "";
  const std::string camera = "camera: {width: 8, height: 6, fx: 10, fy: 10, cx: 4, cy: 3}\n";
  std::ofstream(dir / "block.yaml") << camera << "images: images\norientation: orientation.txt\n";
  ExpectInputErrorFor([&] { ReadBlock(dir / "block.yaml", NoSizeCheck(BlockFormat::kYaml)); },
                      "block.yaml", "expected a mapping for orientation");
  std::ofstream(dir / "block.yaml") << "camera: hello\nimages: images\n"
                                       "orientation: {file: orientation.txt}\n";
  ExpectInputErrorFor([&] { ReadBlock(dir / "block.yaml", NoSizeCheck(BlockFormat::kYaml)); },
                      "block.yaml", "expected a camera mapping");
  std::ofstream(dir / "block.yaml") << "cameras: [hello]\nimages: images\n"
                                       "orientation: {file: orientation.txt}\n";
  ExpectInputErrorFor([&] { ReadBlock(dir / "block.yaml", NoSizeCheck(BlockFormat::kYaml)); },
                      "block.yaml", "expected a mapping for camera");
}

// The read buffer was moved with memmove(nullptr, ...) before its first fill.
TEST(ReaderFuzzRegression, PlyEmptyFile) {
  const fs::path file = test::ScratchDir() / "empty.ply";
  std::ofstream(file) << "";
  ExpectInputErrorFor([&] { ReadPly(file); }, "empty.ply");
}

// A WKT record of length 0 went through strnlen(nullptr, 0).
TEST(ReaderFuzzRegression, LasEmptyWktRecord) {
  const fs::path file = test::ScratchDir() / "cloud.las";
  std::vector<PointRecord> points(3);
  for (int i = 0; i < 3; ++i) points[i].x = 500000 + i;
  LasWriteOptions o;
  o.crs = "EPSG:32632";
  WriteLas(file, points, o);
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    bytes = s.str();
  }
  uint16_t header_size = 0;
  std::memcpy(&header_size, &bytes[94], 2);
  uint32_t vlrs = 0;
  std::memcpy(&vlrs, &bytes[100], 4);
  ASSERT_GE(vlrs, 1u) << "the writer stores the CRS as a VLR";
  ASSERT_EQ(bytes.substr(header_size + 2, 16).c_str(), std::string("LASF_Projection"));
  // Length 0: the payload's bytes stay in the file, unreferenced, before
  // the points (the offset to the points is unchanged).
  bytes[header_size + 20] = 0;
  bytes[header_size + 21] = 0;
  std::ofstream(file, std::ios::binary) << bytes;
  const LasCloud cloud = ReadLas(file);
  EXPECT_EQ(cloud.points.size(), 3u);
  EXPECT_TRUE(cloud.crs_wkt.empty()) << cloud.crs_wkt;
}

// nlohmann's out_of_range escaped the reader.
TEST(ReaderFuzzRegression, OpenSfmNumberPastDoubleRange) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  std::ofstream(dir / "images" / "a.jpg") << "";
  std::ofstream(dir / "reconstruction.json")
      << R"([{"cameras": {"c": {"projection_type": "perspective", "width": 8, "height": 6,)"
      << R"( "focal": 1e999}}, "shots": {}}])";
  ExpectInputErrorFor(
      [&] { ReadBlock(dir / "reconstruction.json", NoSizeCheck(BlockFormat::kOpenSfm)); },
      "reconstruction.json");
}

// A width past int's range was cast to int (undefined behaviour).
TEST(ReaderFuzzRegression, OpenSfmHugeWidth) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  std::ofstream(dir / "reconstruction.json")
      << R"([{"cameras": {"c": {"projection_type": "perspective", "width": 1.4e16,)"
      << R"( "height": 6, "focal": 1}}, "shots": {}}])";
  ExpectInputErrorFor(
      [&] { ReadBlock(dir / "reconstruction.json", NoSizeCheck(BlockFormat::kOpenSfm)); },
      "reconstruction.json", "expected a width and height of 1 to 1048576 px");
}

// An image name longer than a file name may be made std::filesystem throw
// its own filesystem_error (ENAMETOOLONG) while looking the image up.
TEST(ReaderFuzzRegression, ColmapImageNameLongerThanAFileName) {
  const fs::path dir = test::ScratchDir();
  fs::create_directories(dir / "images");
  const std::string name(300, 'x');
  std::ofstream(dir / "cameras.txt") << "1 PINHOLE 640 480 500 500 320 240\n";
  std::ofstream(dir / "images.txt") << "1 1 0 0 0 0 0 0 1 " << name << "\n\n";
  ExpectInputErrorFor([&] { ReadBlock(dir, NoSizeCheck(BlockFormat::kColmap)); }, "images.txt",
                      "no image '" + name + "'");
}

}  // namespace
}  // namespace sapmvs

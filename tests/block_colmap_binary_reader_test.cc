// COLMAP's binary model: the same block written as text and as binary must
// read to the same cameras, and malformed files must fail in one line.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <fstream>
#include <iomanip>

#include "cli_test_util.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// Little-endian bytes, as COLMAP writes them.
class Bytes {
 public:
  template <typename T>
  Bytes& Put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    data_.append(b, sizeof(T));
    return *this;
  }
  Bytes& Name(const std::string& s) {
    data_.append(s);
    data_.push_back('\0');
    return *this;
  }
  void Write(const fs::path& path) const { std::ofstream(path, std::ios::binary) << data_; }
  const std::string& str() const { return data_; }

 private:
  std::string data_;
};

struct Model {
  Bytes cameras, images, points;
};

// The block as COLMAP would write it: camera i+1 is OPENCV (model id 4) with
// the block's distortion, image i+1 uses it, with a few 2D points each.
Model ToColmap(const Block& block) {
  Model m;
  m.cameras.Put<uint64_t>(block.images.size());
  m.images.Put<uint64_t>(block.images.size());
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Camera& c = block.images[i].camera;
    const Intrinsics& k = c.intrinsics();
    m.cameras.Put<uint32_t>(i + 1).Put<int32_t>(4).Put<uint64_t>(k.width).Put<uint64_t>(k.height);
    for (double v : {k.fx, k.fy, k.cx + 0.5, k.cy + 0.5, k.distortion.k1, k.distortion.k2,
                     k.distortion.p1, k.distortion.p2}) {
      m.cameras.Put(v);
    }
    const Eigen::Quaterniond q(c.rotation());
    const Eigen::Vector3d t = -c.rotation() * c.center();
    m.images.Put<uint32_t>(i + 1);
    for (double v : {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()}) m.images.Put(v);
    m.images.Put<uint32_t>(i + 1).Name(block.images[i].name).Put<uint64_t>(i);
    for (size_t j = 0; j < i; ++j) m.images.Put(100.5 + j).Put(200.5).Put<uint64_t>(j);
  }
  m.points.Put<uint64_t>(2);
  for (int p = 0; p < 2; ++p) {
    m.points.Put<uint64_t>(p + 1).Put(0.5 + p).Put(1.5).Put(2.5);
    m.points.Put<uint8_t>(10).Put<uint8_t>(20).Put<uint8_t>(30).Put(0.4).Put<uint64_t>(p + 1);
    for (int j = 0; j <= p; ++j) m.points.Put<uint32_t>(j + 1).Put<uint32_t>(j);
  }
  return m;
}

// The same cameras as cameras.txt / images.txt (OPENCV, full precision).
void WriteText(const Block& block, const fs::path& dir) {
  std::ofstream cams(dir / "cameras.txt"), ims(dir / "images.txt");
  cams << std::setprecision(17);
  ims << std::setprecision(17);
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Camera& c = block.images[i].camera;
    const Intrinsics& k = c.intrinsics();
    cams << i + 1 << " OPENCV " << k.width << " " << k.height << " " << k.fx << " " << k.fy << " "
         << k.cx + 0.5 << " " << k.cy + 0.5 << " " << k.distortion.k1 << " " << k.distortion.k2
         << " " << k.distortion.p1 << " " << k.distortion.p2 << "\n";
    const Eigen::Quaterniond q(c.rotation());
    const Eigen::Vector3d t = -c.rotation() * c.center();
    ims << i + 1 << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " " << t.x()
        << " " << t.y() << " " << t.z() << " " << i + 1 << " " << block.images[i].name << "\n\n";
  }
}

// A project folder `name` in the test's scratch folder: images/ with empty
// stand-ins (sizes are not checked) and the model in sparse/0.
fs::path Project(const Block& block, bool text, bool binary, const std::string& name) {
  static std::string test_name;
  static fs::path scratch;
  const std::string current = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  if (current != test_name) {
    test_name = current;
    scratch = test::ScratchDir();
  }
  const fs::path dir = scratch / name;
  fs::create_directories(dir / "images");
  fs::create_directories(dir / "sparse" / "0");
  for (const BlockImage& im : block.images) std::ofstream(dir / "images" / im.name) << "";
  const fs::path model = dir / "sparse" / "0";
  if (text) WriteText(block, model);
  if (binary) {
    const Model m = ToColmap(block);
    m.cameras.Write(model / "cameras.bin");
    m.images.Write(model / "images.bin");
    m.points.Write(model / "points3D.bin");
  }
  return dir;
}

BlockReadOptions NoSizeCheck() {
  BlockReadOptions o;
  o.check_image_sizes = false;
  return o;
}

// Two cameras with distortion and an oblique pose, independent of the data.
Block SmallBlock() {
  Block b;
  for (int i = 0; i < 2; ++i) {
    Intrinsics k = Intrinsics::FromPixels(2800 + 10 * i, 2810, 1535.25, 1023.75, 3072, 2048);
    k.distortion.k1 = -0.1 + 0.01 * i;
    k.distortion.k2 = 0.02;
    k.distortion.p1 = 0.001;
    k.distortion.p2 = -0.002;
    BlockImage im;
    im.name = "img_" + std::to_string(i) + ".jpg";
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(0.3 + i, Eigen::Vector3d(0.2, -1, 0.5).normalized()).toRotationMatrix();
    im.camera = Camera(k, r, Eigen::Vector3d(10.0 * i, -3, 250.5));
    b.images.push_back(im);
  }
  return b;
}

void ExpectSameCameras(const Block& a, const Block& b) {
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    SCOPED_TRACE(a.images[i].name);
    EXPECT_EQ(a.images[i].name, b.images[i].name);
    if (!a.images[i].camera_name.empty()) {
      EXPECT_EQ(a.images[i].camera_name, b.images[i].camera_name);
    }
    const Intrinsics &ka = a.images[i].camera.intrinsics(), &kb = b.images[i].camera.intrinsics();
    EXPECT_EQ(ka.width, kb.width);
    EXPECT_EQ(ka.height, kb.height);
    for (auto [x, y] : {std::pair{ka.fx, kb.fx},
                        {ka.fy, kb.fy},
                        {ka.cx, kb.cx},
                        {ka.cy, kb.cy},
                        {ka.distortion.k1, kb.distortion.k1},
                        {ka.distortion.k2, kb.distortion.k2},
                        {ka.distortion.p1, kb.distortion.p1},
                        {ka.distortion.p2, kb.distortion.p2}}) {
      EXPECT_NEAR(x, y, 1e-9);
    }
    EXPECT_LT((a.images[i].camera.rotation() - b.images[i].camera.rotation()).norm(), 1e-9);
    EXPECT_LT((a.images[i].camera.center() - b.images[i].camera.center()).norm(), 1e-9);
  }
}

TEST(ColmapBinaryReader, MatchesTextModelOfTheSameBlock) {
  const Block ref = SmallBlock();
  const fs::path text = Project(ref, true, false, "text"),
                 binary = Project(ref, false, true, "binary");
  EXPECT_EQ(DetectBlockFormat(binary), BlockFormat::kColmap);
  const Block t = ReadBlock(text, NoSizeCheck());
  for (const fs::path& given :
       {binary, binary / "sparse" / "0", binary / "sparse" / "0" / "cameras.bin"}) {
    SCOPED_TRACE(given.string());
    const Block b = ReadBlock(given, NoSizeCheck());
    ExpectSameCameras(t, b);
    ExpectSameCameras(ref, b);
    ASSERT_EQ(b.sparse_points.size(), 2u);
    EXPECT_LT((b.sparse_points[1] - Eigen::Vector3d(1.5, 1.5, 2.5)).norm(), 1e-12);
  }
}

TEST(ColmapBinaryReader, MatchesTextModelOfHerzJesu) {
  const fs::path herz = test::HerzJesu();
  SAPMVS_REQUIRE_PATH(herz);
  const Block ref = ReadBlock(herz, NoSizeCheck());
  const Block t = ReadBlock(Project(ref, true, false, "text"), NoSizeCheck());
  const Block b = ReadBlock(Project(ref, false, true, "binary"), NoSizeCheck());
  ExpectSameCameras(t, b);
}

TEST(ColmapBinaryReader, BinaryWinsWhenBothModelsArePresent) {
  Block ref = SmallBlock();
  const fs::path dir = Project(ref, false, true, "both");
  // A text model that differs (other focal), so the test sees which was read.
  Block other = ref;
  Intrinsics k = other.images[0].camera.intrinsics();
  k.fx += 100;
  other.images[0].camera = other.images[0].camera.WithIntrinsics(k);
  WriteText(other, dir / "sparse" / "0");
  ExpectSameCameras(ref, ReadBlock(dir, NoSizeCheck()));
  // Naming a text file reads the text model.
  ExpectSameCameras(other, ReadBlock(dir / "sparse" / "0" / "images.txt", NoSizeCheck()));
}

struct Corrupt {
  std::string name;
  std::string file;  // which file of the model is replaced
  std::function<std::string(const Model&)> bytes;
  std::string expect;
};
void PrintTo(const Corrupt& c, std::ostream* os) { *os << c.name; }

class ColmapBinaryMalformed : public ::testing::TestWithParam<Corrupt> {};

fs::path CorruptProject(const Corrupt& c) {
  const fs::path dir = Project(SmallBlock(), false, true, "corrupt");
  const Model m = ToColmap(SmallBlock());
  std::ofstream(dir / "sparse" / "0" / c.file, std::ios::binary) << c.bytes(m);
  return dir;
}

TEST_P(ColmapBinaryMalformed, FailsInOneLineNamingTheFile) {
  const Corrupt& c = GetParam();
  const fs::path dir = CorruptProject(c);
  test::ExpectInputError([&] { ReadBlock(dir, NoSizeCheck()); }, c.file, 0, c.expect);
}

// The CLI prints the same one line and exits 1 (info reads only the block).
TEST_P(ColmapBinaryMalformed, CliExitsOneWithOneLine) {
  const Corrupt& c = GetParam();
  const fs::path dir = CorruptProject(c);
  const test::CliResult r = test::RunCli("info " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_EQ(test::CountLines(r.err), 1) << r.err;
  EXPECT_EQ(r.err.rfind("sapmvs: " + (dir / "sparse" / "0" / c.file).string() + ": ", 0), 0u)
      << r.err;
  EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
}

std::string Patch(std::string s, size_t at, uint64_t value, size_t size) {
  std::memcpy(&s[at], &value, size);
  return s;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ColmapBinaryMalformed,
    ::testing::Values(
        Corrupt{"TruncatedCameras", "cameras.bin",
                [](const Model& m) { return m.cameras.str().substr(0, 50); }, "truncated"},
        Corrupt{"TruncatedImages", "images.bin",
                [](const Model& m) { return m.images.str().substr(0, m.images.str().size() - 5); },
                "truncated"},
        Corrupt{"EmptyPoints", "points3D.bin", [](const Model&) { return std::string(); },
                "truncated"},
        Corrupt{"UnknownModelId", "cameras.bin",
                [](const Model& m) { return Patch(m.cameras.str(), 8 + 4, 99, 4); },
                "unsupported camera model id 99"},
        Corrupt{"FisheyeModelId", "cameras.bin",
                [](const Model& m) { return Patch(m.cameras.str(), 8 + 4, 5, 4); },
                "model id 5 (OPENCV_FISHEYE)"},
        Corrupt{"CameraCountPastEnd", "cameras.bin",
                [](const Model& m) { return Patch(m.cameras.str(), 0, uint64_t{1} << 60, 8); },
                "the number of cameras is 1152921504606846976"},
        Corrupt{"ImageCountPastEnd", "images.bin",
                [](const Model& m) { return Patch(m.images.str(), 0, ~uint64_t{0}, 8); },
                "the number of images is"},
        // The first image's 2D point count (after id, pose, camera and name).
        Corrupt{"PointCountPastEnd", "images.bin",
                [](const Model& m) {
                  return Patch(m.images.str(), 8 + 4 + 56 + 4 + 10, uint64_t{1} << 40, 8);
                },
                "the number of 2D points is 1099511627776"},
        Corrupt{"TrailingBytes", "points3D.bin",
                [](const Model& m) { return m.points.str() + "xyz"; }, "3 bytes after the last"},
        Corrupt{"UnknownCamera", "images.bin",
                [](const Model& m) { return Patch(m.images.str(), 8 + 4 + 56, 7, 4); },
                "unknown CAMERA_ID 7"},
        Corrupt{
            "NanFocal", "cameras.bin",
            [](const Model& m) { return Patch(m.cameras.str(), 8 + 24, 0x7ff8000000000000ull, 8); },
            "expected a finite camera parameter"}),
    [](const auto& p) { return p.param.name; });

}  // namespace
}  // namespace sapmvs

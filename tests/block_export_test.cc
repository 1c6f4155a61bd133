#include "sapmvs/block/block_export.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "export_test_block.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/export_frame.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

using test::Slurp;

// Points seen by the cameras: a grid of pixels of every image, at three
// depths around the ground's.
std::vector<Eigen::Vector3d> ScenePoints(const std::vector<Camera>& cameras) {
  std::vector<Eigen::Vector3d> points;
  for (const Camera& c : cameras) {
    for (double fu : {0.05, 0.5, 0.95})
      for (double fv : {0.05, 0.5, 0.95})
        for (double depth : {60.0, 100.0, 140.0})
          points.push_back(c.BackProject({fu * (c.width() - 1), fv * (c.height() - 1)}, depth));
  }
  return points;
}

// The largest difference, in pixels, between projections through `expected`
// and `actual` (image by image) of points the expected cameras see.
double MaxProjectionError(const std::vector<Camera>& expected, const Block& actual) {
  EXPECT_EQ(actual.images.size(), expected.size());
  double worst = 0;
  const std::vector<Eigen::Vector3d> points = ScenePoints(expected);
  for (size_t i = 0; i < expected.size() && i < actual.images.size(); ++i) {
    const Camera& a = actual.images[i].camera;
    EXPECT_EQ(a.width(), expected[i].width());
    EXPECT_EQ(a.height(), expected[i].height());
    EXPECT_TRUE(a.intrinsics().distortion.IsZero());
    for (const Eigen::Vector3d& x : points) {
      const Eigen::Vector2d e = expected[i].Project(x);
      if (!e.allFinite()) continue;
      const double d = (a.Project(x) - e).norm();
      worst = std::isfinite(d) ? std::max(worst, d) : HUGE_VAL;  // NaN: not in front
    }
  }
  return worst;
}

// The cameras an export at `level` must give back: pinhole, scaled.
std::vector<Camera> Expected(const Block& block, int level) {
  std::vector<Camera> cameras;
  for (const BlockImage& im : block.images)
    cameras.push_back(im.camera.Pinhole().Scaled(std::ldexp(1.0, -level)));
  return cameras;
}

TEST(ExportOptions, DefaultsAndBoundaries) {
  ExportOptions o;
  EXPECT_NE(o.Problem().find("output folder"), std::string::npos);
  o.out = "/tmp/x";
  EXPECT_EQ(o.Problem(), "");
  EXPECT_TRUE(o.Check());
  EXPECT_EQ(o.Level(), 1);  // PMVS2's default
  o.format = ExportFormat::kColmap;
  EXPECT_EQ(o.Level(), 0);
  for (int bad : {-1, 7}) {
    o.level = bad;
    EXPECT_NE(o.Problem().find("level in 0..6"), std::string::npos) << o.Problem();
  }
  o.level = 6;
  EXPECT_EQ(o.Problem(), "");
  o.jpeg_quality = 0;
  EXPECT_NE(o.Problem().find("jpeg_quality"), std::string::npos);
}

TEST(ExportOptions, ParsesFormats) {
  EXPECT_EQ(ParseExportFormat("pmvs"), ExportFormat::kPmvs);
  EXPECT_EQ(ParseExportFormat("colmap"), ExportFormat::kColmap);
  try {
    ParseExportFormat("ply");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "unknown export format 'ply': expected pmvs or colmap");
  }
}

class BlockExportTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    block_ = ReadBlock(test::WriteDistortedBlock(dir_ / "src"));
    out_ = dir_ / "out";
  }
  ExportSummary Export(ExportFormat format, std::optional<int> level = std::nullopt) {
    ExportOptions o;
    o.out = out_;
    o.format = format;
    o.level = level;
    o.progress = false;
    return ExportBlock(block_, o);
  }
  Block block_;
  fs::path out_;
};

TEST_F(BlockExportTest, PmvsRoundTripGivesTheSameCameras) {
  ASSERT_GT(block_.origin.norm(), 5e6);  // UTM-sized: float32 would lose centimetres
  const ExportSummary s = Export(ExportFormat::kPmvs, 2);
  EXPECT_EQ(s.images, 3);
  EXPECT_EQ(s.level, 2);
  for (const char* f : {"visualize/00000000.jpg", "visualize/00000002.jpg", "txt/00000000.txt",
                        "txt/00000002.txt", "option", "sapmvs_frame.json"})
    EXPECT_TRUE(fs::is_regular_file(out_ / f)) << f;
  EXPECT_TRUE(fs::is_directory(out_ / "models"));
  EXPECT_TRUE(fs::is_empty(out_ / "models"));
  const std::string option = Slurp(out_ / "option");
  EXPECT_NE(option.find("level 2\ncsize 2\nthreshold 0.7\nwsize 7\nminImageNum 3\nCPU "),
            std::string::npos)
      << option;
  EXPECT_NE(option.find("useVisData 0\nsequence -1\nmaxAngle 10\nquad 2.0\ntimages -1 0 3\n"
                        "oimages 0\n"),
            std::string::npos)
      << option;
  // The projection matrices are local: in world coordinates K t would be
  // about f times the origin, 1e8 here.
  std::istringstream p(Slurp(out_ / "txt/00000001.txt").substr(8));
  double largest = 0;
  for (double v; p >> v;) largest = std::max(largest, std::abs(v));
  EXPECT_GT(largest, 1);
  EXPECT_LT(largest, 1e5);

  const Block back = ReadBlock(out_);
  EXPECT_EQ(back.format, "pmvs");
  EXPECT_LT(MaxProjectionError(Expected(block_, 0), back), 1e-6);  // full-resolution images
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.images[i].name, block_.images[i].name);
    EXPECT_LT((back.images[i].camera.center() - block_.images[i].camera.center()).norm(), 1e-6);
  }
  EXPECT_EQ(back.crs, "EPSG:32632");
  ASSERT_TRUE(back.ground_height);
  EXPECT_EQ(*back.ground_height, 300.5);
  EXPECT_EQ(back.origin, block_.origin);
}

TEST_F(BlockExportTest, ColmapRoundTripGivesTheSameCamerasAtEachLevel) {
  for (int level : {0, 1, 2}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const ExportSummary s = Export(ExportFormat::kColmap, level);
    EXPECT_EQ(s.cameras, 1);  // one shared interior orientation
    const Block back = ReadBlock(out_);
    EXPECT_EQ(back.format, "colmap");
    const std::vector<Camera> expected = Expected(block_, level);
    EXPECT_LT(MaxProjectionError(expected, back), 1e-6);
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(back.images[i].name, block_.images[i].name);  // a.png, b.jpg, c.tif
      EXPECT_EQ(back.images[i].path, out_ / "images" / block_.images[i].name);
      const ImageSize size = ReadImageSize(back.images[i].path);
      EXPECT_EQ(size.width, expected[i].width());
      EXPECT_EQ(size.height, expected[i].height());
    }
    EXPECT_EQ(back.crs, "EPSG:32632");
  }
}

TEST_F(BlockExportTest, ColmapImagesAreTheUndistortedOnesAtTheLevel) {
  Export(ExportFormat::kColmap, 1);
  const LoadedImage full = LoadUndistorted(block_.images[0]);
  const cv::Mat expected = ResampleToLevel(full.pixels, 1, Expected(block_, 1)[0].width(),
                                           Expected(block_, 1)[0].height());
  const cv::Mat written = cv::imread((out_ / "images" / "a.png").string(), cv::IMREAD_COLOR);
  ASSERT_EQ(written.size(), expected.size());
  EXPECT_EQ(cv::norm(written, expected, cv::NORM_INF), 0);  // PNG is lossless
}

TEST_F(BlockExportTest, SideFileHoldsOriginCrsSourceAndLevel) {
  Export(ExportFormat::kColmap, 1);
  const nlohmann::json j = nlohmann::json::parse(Slurp(out_ / "sapmvs_frame.json"));
  EXPECT_EQ(j.at("format"), "colmap");
  EXPECT_EQ(j.at("level"), 1);
  EXPECT_EQ(j.at("crs"), "EPSG:32632");
  EXPECT_EQ(j.at("source"), fs::absolute(dir_ / "src" / "block.yaml").lexically_normal().string());
  EXPECT_EQ(j.at("sapmvs_version"), SAPMVS_VERSION);
  const std::vector<double> origin = j.at("origin");
  ASSERT_EQ(origin.size(), 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(origin[k], block_.origin[k]);  // bit for bit
  const std::optional<ExportFrame> frame = ReadExportFrame(out_);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->origin, block_.origin);
  EXPECT_EQ(frame->images, (std::vector<std::string>{"a.png", "b.jpg", "c.tif"}));
}

TEST_F(BlockExportTest, ColmapWithoutPointsWritesTheHeaderOnly) {
  EXPECT_EQ(Export(ExportFormat::kColmap).points, 0);
  const std::string text = Slurp(out_ / "sparse/0/points3D.txt");
  EXPECT_EQ(text.rfind("# 3D point list", 0), 0u) << text;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) EXPECT_EQ(line.rfind("#", 0), 0u) << line;
  EXPECT_TRUE(ReadBlock(out_).sparse_points.empty());
}

TEST_F(BlockExportTest, ColmapWithPointsGivesThemBackInTheWorldFrame) {
  block_.sparse_points = {block_.origin + Eigen::Vector3d(1.25, -3.5, -99.75),
                          block_.origin + Eigen::Vector3d(-20.125, 7.0, -100.5)};
  EXPECT_EQ(Export(ExportFormat::kColmap).points, 2);
  const Block back = ReadBlock(out_);
  ASSERT_EQ(back.sparse_points.size(), 2u);
  for (size_t i = 0; i < 2; ++i)
    EXPECT_LT((back.sparse_points[i] - block_.sparse_points[i]).norm(), 1e-9);
}

TEST_F(BlockExportTest, RefusesAForeignFolderAndLeavesItAlone) {
  fs::create_directories(out_);
  std::ofstream(out_ / "notes.txt") << "mine\n";
  try {
    Export(ExportFormat::kPmvs);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind(out_.string() + ": ", 0), 0u) << what;
    EXPECT_NE(what.find("not written by sapmvs export"), std::string::npos) << what;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(out_), fs::directory_iterator()), 1);
  EXPECT_EQ(Slurp(out_ / "notes.txt"), "mine\n");
}

TEST_F(BlockExportTest, ReexportReplacesItsOwnFolder) {
  Export(ExportFormat::kPmvs);
  block_.images.pop_back();
  Export(ExportFormat::kPmvs);  // fewer images: the third's files must go
  EXPECT_FALSE(fs::exists(out_ / "txt/00000002.txt"));
  EXPECT_FALSE(fs::exists(out_ / "visualize/00000002.jpg"));
  EXPECT_EQ(ReadBlock(out_).images.size(), 2u);

  Export(ExportFormat::kColmap, 1);  // another format into the same folder
  EXPECT_FALSE(fs::exists(out_ / "txt"));
  EXPECT_FALSE(fs::exists(out_ / "visualize"));
  EXPECT_FALSE(fs::exists(out_ / "option"));
  EXPECT_EQ(DetectBlockFormat(out_), BlockFormat::kColmap);
  EXPECT_LT(MaxProjectionError(Expected(block_, 1), ReadBlock(out_)), 1e-6);
}

TEST_F(BlockExportTest, UnfinishedExportIsNotReadAsABlock) {
  Export(ExportFormat::kPmvs);
  fs::remove(out_ / "sapmvs_frame.json");  // as if killed before the end
  try {
    ReadBlock(out_);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unfinished sapmvs export"), std::string::npos)
        << e.what();
  }
  Export(ExportFormat::kPmvs);  // the marker still proves the folder is ours
  EXPECT_EQ(ReadBlock(out_).images.size(), 3u);
}

TEST_F(BlockExportTest, RefusesToOverwriteTheImagesItReads) {
  Export(ExportFormat::kColmap);
  block_ = ReadBlock(out_);
  try {
    Export(ExportFormat::kColmap);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("holds the block's own image"), std::string::npos)
        << e.what();
  }
}

TEST_F(BlockExportTest, SideFileOfAnotherFormatIsAnError) {
  Export(ExportFormat::kColmap);
  nlohmann::json j = nlohmann::json::parse(Slurp(out_ / "sapmvs_frame.json"));
  j["format"] = "pmvs";
  std::ofstream(out_ / "sapmvs_frame.json") << j.dump();
  test::ExpectInputError([&] { ReadBlock(out_); }, "sapmvs_frame.json", 0,
                         "written for a pmvs export");
}

// The real distorted UAV block, in UTM 51N.
TEST(BlockExportOdm, BothFormatsGiveBackTheUndistortedCameras) {
  const fs::path yaml = test::TestDir() / "blocks" / "odm.yaml";
  SAPMVS_REQUIRE_PATH(test::SharedDir() / "datasets/orthority_ngi_odm/odm/images");
  const Block block = ReadBlock(yaml);
  ASSERT_FALSE(block.images[0].camera.intrinsics().distortion.IsZero());
  const fs::path dir = test::ScratchDir();
  for (const auto& [format, level] :
       {std::pair{ExportFormat::kPmvs, 1}, std::pair{ExportFormat::kColmap, 1}}) {
    ExportOptions o;
    o.out = dir / ToString(format);
    o.format = format;
    o.level = level;
    o.progress = false;
    ExportBlock(block, o);
    const Block back = ReadBlock(o.out);
    const int image_level = format == ExportFormat::kPmvs ? 0 : level;
    EXPECT_LT(MaxProjectionError(Expected(block, image_level), back), 1e-6) << ToString(format);
    EXPECT_EQ(back.crs, "EPSG:32651");
    EXPECT_TRUE(fs::equivalent(back.dem, block.dem)) << back.dem;
    EXPECT_EQ(back.origin, block.origin);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sapmvs

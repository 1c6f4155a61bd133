#include "sapmvs/block/block_reader.h"

#include <gtest/gtest.h>

#include <fstream>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using test::SharedDir;

TEST(BlockFormat, DetectedFromThePathGiven) {
  SAPMVS_REQUIRE_PATH(SharedDir() / "datasets");
  const fs::path odm = SharedDir() / "datasets/orthority_ngi_odm/odm";
  EXPECT_EQ(DetectBlockFormat(test::TestDir() / "blocks" / "ngi.yaml"), BlockFormat::kYaml);
  EXPECT_EQ(DetectBlockFormat(odm), BlockFormat::kOpenSfm);
  EXPECT_EQ(DetectBlockFormat(odm / "opensfm"), BlockFormat::kOpenSfm);
  EXPECT_EQ(DetectBlockFormat(odm / "opensfm" / "reconstruction.json"), BlockFormat::kOpenSfm);
  const fs::path hj = test::HerzJesu();
  EXPECT_EQ(DetectBlockFormat(hj), BlockFormat::kStrecha);
  EXPECT_EQ(DetectBlockFormat(hj / "gt_dense_cameras"), BlockFormat::kStrecha);
  EXPECT_EQ(DetectBlockFormat(hj / "gt_dense_cameras" / "0003.jpg.camera"), BlockFormat::kStrecha);
}

TEST(BlockFormat, ParseAndRejectUnknown) {
  EXPECT_EQ(ParseBlockFormat("colmap"), BlockFormat::kColmap);
  EXPECT_EQ(ParseBlockFormat("pmvs"), BlockFormat::kPmvs);
  try {
    ParseBlockFormat("bundler");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown block format 'bundler'"), std::string::npos);
  }
}

TEST(BlockFormat, MissingOrUnknownPathsSayWhatWasExpected) {
  const fs::path dir = test::ScratchDir();
  try {
    ReadBlock(dir / "nope.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.yaml: block not found"), std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "cloud.ply") << "ply\n";
  EXPECT_THROW(ReadBlock(dir / "cloud.ply"), Error);
  try {
    ReadBlock(dir);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no block found in folder"), std::string::npos)
        << e.what();
  }
}

TEST(BlockFormat, ForcedFormatOverridesDetection) {
  SAPMVS_REQUIRE_PATH(test::HerzJesu());
  BlockReadOptions options;
  options.format = BlockFormat::kColmap;
  EXPECT_THROW(ReadBlock(test::HerzJesu(), options), Error);
  options.format = BlockFormat::kStrecha;
  EXPECT_EQ(ReadBlock(test::HerzJesu(), options).images.size(), 8u);
}

TEST(BlockReadOptions, CheckRejectsAMissingImageFolder) {
  BlockReadOptions options;
  EXPECT_TRUE(options.Check());
  options.image_dir = "/nonexistent/folder";
  EXPECT_FALSE(options.Check());
}

TEST(LocalOrigin, RoundNumberNearTheCentres) {
  std::vector<BlockImage> images(2);
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 399.5, 1000, 800);
  images[0].camera = Camera(k, Eigen::Matrix3d::Identity(), {500123.4567, 5400321.987, 712.3});
  images[1].camera = Camera(k, Eigen::Matrix3d::Identity(), {501123.4567, 5400521.987, 713.3});
  const Eigen::Vector3d o = ChooseLocalOrigin(images);
  EXPECT_DOUBLE_EQ(o.x(), 500623.0);  // extent 1000 -> 1-unit steps
  EXPECT_DOUBLE_EQ(o.y(), 5400422.0);
  EXPECT_DOUBLE_EQ(o.z(), 713.0);
  // A free-network block 2 units wide keeps millimetre-level origins.
  images[0].camera = Camera(k, Eigen::Matrix3d::Identity(), {0.1234, -1.31, -1.3});
  images[1].camera = Camera(k, Eigen::Matrix3d::Identity(), {2.1234, -1.29, -1.3});
  const Eigen::Vector3d f = ChooseLocalOrigin(images);
  EXPECT_NEAR(f.x(), 1.123, 1e-12);
  EXPECT_NEAR(f.y(), -1.3, 1e-12);
}

}  // namespace
}  // namespace sapmvs

#include "util/image_codec.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "sapmvs/util/error.h"
#include "test_util.h"
#include "util/gdal_image_files.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

using ImageCodecTest = test::ScratchTest;

// Odd sizes, so that row padding and strides are exercised.
cv::Mat RandomImage(int type, unsigned seed) {
  cv::Mat m(23, 37, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  return m;
}

void WriteFile(const fs::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

double MaxDifference(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return 1e9;
  return cv::norm(a, b, cv::NORM_INF);
}

TEST_F(ImageCodecTest, LosslessFormatsRoundTripAndOpenCvReadsThem) {
  const cv::Mat image = RandomImage(CV_8UC3, 1);
  const std::vector<std::pair<ImageEncoding, std::string>> formats = {{ImageEncoding::kPng, "png"},
                                                                      {ImageEncoding::kTiff, "tif"},
                                                                      {ImageEncoding::kBmp, "bmp"},
                                                                      {ImageEncoding::kPpm, "ppm"}};
  for (const auto& [encoding, ext] : formats) {
    SCOPED_TRACE(ext);
    ASSERT_TRUE(CanEncode(encoding));
    const fs::path file = dir_ / ("a." + ext);
    WriteFile(file, EncodeImage(image, encoding, file.string()));
    EXPECT_EQ(MaxDifference(DecodeImageFile(file), image), 0);
    // An independent decoder sees the same pixels in the same channel order.
    EXPECT_EQ(MaxDifference(cv::imread(file.string(), cv::IMREAD_COLOR), image), 0);
  }
}

// What a plan counts GDAL's libraries for (GdalBytesToMatch): JPEG and PNG
// by their first bytes, whatever the name; not TIFF, nor a missing file.
TEST_F(ImageCodecTest, JpegAndPngAloneAreDecodedWithoutGdal) {
  const cv::Mat image = RandomImage(CV_8UC3, 4);
  const std::vector<std::tuple<ImageEncoding, std::string, bool>> formats = {
      {ImageEncoding::kPng, "a.tif", true},
      {ImageEncoding::kJpeg, "b.png", true},
      {ImageEncoding::kTiff, "c.jpg", false},
      {ImageEncoding::kBmp, "d.bmp", false}};
  for (const auto& [encoding, name, without] : formats) {
    WriteFile(dir_ / name, EncodeImage(image, encoding, name));
    EXPECT_EQ(DecodedWithoutGdal(dir_ / name), without) << name;
  }
  EXPECT_FALSE(DecodedWithoutGdal(dir_ / "missing.jpg"));
}

TEST_F(ImageCodecTest, GreyIsRepeatedInTheThreeChannels) {
  const cv::Mat grey = RandomImage(CV_8UC1, 2);
  const fs::path file = dir_ / "grey.png";
  WriteFile(file, EncodeImage(grey, ImageEncoding::kPng, file.string()));
  cv::Mat expected;
  cv::merge(std::vector<cv::Mat>{grey, grey, grey}, expected);
  EXPECT_EQ(MaxDifference(DecodeImageFile(file), expected), 0);
}

TEST_F(ImageCodecTest, JpegIsCloseAndItsQualityApplies) {
  // Smooth, so that JPEG at a high quality keeps it within a few levels.
  cv::Mat image(41, 53, CV_8UC3);
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c)
      image.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<uchar>(3 * c), static_cast<uchar>(4 * r),
                                            static_cast<uchar>(100 + c + r));
  const fs::path file = dir_ / "a.jpg";
  const std::vector<unsigned char> fine = EncodeImage(image, ImageEncoding::kJpeg, "a", 95);
  const std::vector<unsigned char> coarse = EncodeImage(image, ImageEncoding::kJpeg, "a", 20);
  EXPECT_LT(coarse.size(), fine.size());
  WriteFile(file, fine);
  EXPECT_LE(MaxDifference(DecodeImageFile(file), image), 8);
  EXPECT_EQ(MaxDifference(DecodeImageFile(file), cv::imread(file.string(), cv::IMREAD_COLOR)), 0);
}

// Files as cameras and other tools write them, decoded as OpenCV's imread
// (IMREAD_COLOR) decodes them: 16-bit scaled to 8, alpha dropped, grey
// repeated.
TEST_F(ImageCodecTest, DecodesOtherWritersFilesAsOpenCvDoes) {
  struct Case {
    std::string file;
    cv::Mat pixels;
    double tolerance;  // 16-bit to 8-bit: OpenCV's decoders round differently
  };
  const std::vector<Case> cases = {{"wide.png", RandomImage(CV_16UC3, 3), 1},
                                   {"wide.tif", RandomImage(CV_16UC3, 4), 1},
                                   {"alpha.png", RandomImage(CV_8UC4, 5), 0},
                                   {"grey_wide.png", RandomImage(CV_16UC1, 6), 1},
                                   {"grey.tif", RandomImage(CV_8UC1, 7), 0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const fs::path file = dir_ / c.file;
    ASSERT_TRUE(cv::imwrite(file.string(), c.pixels));
    const cv::Mat expected = cv::imread(file.string(), cv::IMREAD_COLOR);
    ASSERT_EQ(expected.type(), CV_8UC3);
    EXPECT_LE(MaxDifference(DecodeImageFile(file), expected), c.tolerance);
  }
}

// JPEG and PNG are decoded by libjpeg and libpng, not GDAL (image_codec.h):
// the same pixels and sizes as GDAL's drivers give, in every layout.
TEST_F(ImageCodecTest, JpegAndPngDecodeAsGdalDecodesThem) {
  const std::vector<std::pair<std::string, cv::Mat>> cases = {
      {"colour.jpg", RandomImage(CV_8UC3, 8)},  {"grey.jpg", RandomImage(CV_8UC1, 9)},
      {"colour.png", RandomImage(CV_8UC3, 10)}, {"alpha.png", RandomImage(CV_8UC4, 11)},
      {"grey.png", RandomImage(CV_8UC1, 12)},   {"wide.png", RandomImage(CV_16UC3, 13)}};
  for (const auto& [name, pixels] : cases) {
    SCOPED_TRACE(name);
    const fs::path file = dir_ / name;
    ASSERT_TRUE(cv::imwrite(file.string(), pixels));
    const cv::Mat here = DecodeImageFile(file);
    ASSERT_EQ(here.type(), CV_8UC3);
    // GDAL rounds 16-bit samples to 8 bits, libpng (and OpenCV) truncate.
    EXPECT_LE(MaxDifference(here, DecodeImageWithGdal(file)), pixels.depth() == CV_16U ? 1 : 0);
    EXPECT_EQ(ReadImageFileSize(file), ReadImageSizeWithGdal(file));
    EXPECT_EQ(ReadImageFileSize(file), cv::Size(pixels.cols, pixels.rows));
  }
  // A palette PNG, as GDAL writes one.
  GDALAllRegister();
  const fs::path palette = dir_ / "palette.png";
  {
    std::unique_ptr<GDALDataset> mem(
        GetGDALDriverManager()->GetDriverByName("MEM")->Create("", 7, 5, 1, GDT_Byte, nullptr));
    GDALColorTable table;
    for (int i = 0; i < 3; ++i) {
      const GDALColorEntry e = {static_cast<short>(40 * i), 7, static_cast<short>(250 - i), 255};
      table.SetColorEntry(i, &e);
    }
    ASSERT_EQ(mem->GetRasterBand(1)->SetColorTable(&table), CE_None);
    std::vector<GByte> index(35);
    for (int i = 0; i < 35; ++i) index[i] = static_cast<GByte>(i % 3);
    ASSERT_EQ(mem->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 7, 5, index.data(), 7, 5, GDT_Byte, 0,
                                              0, nullptr),
              CE_None);
    GDALClose(GetGDALDriverManager()->GetDriverByName("PNG")->CreateCopy(
        palette.string().c_str(), mem.get(), FALSE, nullptr, nullptr, nullptr));
  }
  EXPECT_EQ(MaxDifference(DecodeImageFile(palette), DecodeImageWithGdal(palette)), 0);
  EXPECT_EQ(DecodeImageFile(palette).at<cv::Vec3b>(0, 1), cv::Vec3b(249, 7, 40));
}

TEST_F(ImageCodecTest, CorruptJpegOrPngNamesTheFileAndTheDecoder) {
  // The magic bytes survive, what follows them does not: the JPEG's tables,
  // the PNG's header, or the middle of the PNG's pixel data (its checksum
  // fails while the rows are read).
  const std::vector<std::pair<std::string, int>> cases = {
      {"bad.jpg", 20}, {"bad.png", 16}, {"bad_data.png", 1500}};
  for (const auto& [name, at] : cases) {
    SCOPED_TRACE(name);
    const fs::path file = dir_ / name;
    ASSERT_TRUE(cv::imwrite(file.string(), RandomImage(CV_8UC3, 14)));
    ASSERT_GT(fs::file_size(file), static_cast<uintmax_t>(at + 64));
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(at);
    const std::string junk(64, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
    f.close();
    try {
      DecodeImageFile(file);
      FAIL() << "decoded a corrupt file";
    } catch (const Error& e) {
      const std::string decoder = name == "bad.jpg" ? "(libjpeg: " : "(libpng: ";
      EXPECT_NE(std::string(e.what()).find(file.string() + ": cannot decode image " + decoder),
                std::string::npos)
          << e.what();
    }
  }
}

TEST_F(ImageCodecTest, ExpandsAPalette) {
  GDALAllRegister();
  const fs::path file = dir_ / "palette.tif";
  {
    std::unique_ptr<GDALDataset> ds(GetGDALDriverManager()->GetDriverByName("GTiff")->Create(
        file.string().c_str(), 5, 3, 1, GDT_Byte, nullptr));
    GDALColorTable table;
    for (int i = 0; i < 4; ++i) {
      const GDALColorEntry e = {static_cast<short>(10 * i), static_cast<short>(20 + i),
                                static_cast<short>(200 - i), 255};
      table.SetColorEntry(i, &e);
    }
    GDALRasterBand* band = ds->GetRasterBand(1);
    ASSERT_EQ(band->SetColorTable(&table), CE_None);
    ASSERT_EQ(band->SetColorInterpretation(GCI_PaletteIndex), CE_None);
    std::vector<GByte> index(15);
    for (int i = 0; i < 15; ++i) index[i] = static_cast<GByte>(i % 4);
    ASSERT_EQ(band->RasterIO(GF_Write, 0, 0, 5, 3, index.data(), 5, 3, GDT_Byte, 0, 0, nullptr),
              CE_None);
  }
  const cv::Mat pixels = DecodeImageFile(file);
  ASSERT_EQ(pixels.type(), CV_8UC3);
  for (int i = 0; i < 15; ++i) {
    const int k = i % 4;
    EXPECT_EQ(pixels.at<cv::Vec3b>(i / 5, i % 5), cv::Vec3b(200 - k, 20 + k, 10 * k)) << i;
  }
}

TEST_F(ImageCodecTest, RefusesWhatIsNotAnImageNamingTheFile) {
  const fs::path text = dir_ / "notes.png";
  std::ofstream(text) << "not an image\n";
  try {
    DecodeImageFile(text);
    FAIL() << "decoded a text file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(text.string() + ": cannot decode image"),
              std::string::npos)
        << e.what();
  }

  const fs::path floats = dir_ / "floats.tif";
  cv::Mat f(4, 6, CV_32FC1, cv::Scalar(0.5));
  ASSERT_TRUE(cv::imwrite(floats.string(), f));
  try {
    DecodeImageFile(floats);
    FAIL() << "decoded float samples";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("Float32 samples, expected 8-bit or 16-bit"),
              std::string::npos)
        << e.what();
  }

  EXPECT_THROW(EncodeImage(f, ImageEncoding::kPng, "f.png"), Error);
  EXPECT_THROW(EncodeImage(cv::Mat(), ImageEncoding::kPng, "empty.png"), Error);
}

}  // namespace
}  // namespace sapmvs

#include "util/gdal_image_files.h"

#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <atomic>
#include <opencv2/core.hpp>

#include "sapmvs/util/error.h"
#include "util/gdal_drivers.h"
#include "util/gdal_messages.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace {

const char* DriverName(ImageEncoding encoding) {
  switch (encoding) {
    case ImageEncoding::kPng:
      return "PNG";
    case ImageEncoding::kJpeg:
      return "JPEG";
    case ImageEncoding::kTiff:
      return "GTiff";
    case ImageEncoding::kBmp:
      return "BMP";
    case ImageEncoding::kPpm:
      return "PNM";
  }
  return "";
}

// A palette image's indices looked up in its colour table.
cv::Mat ExpandPalette(GDALRasterBand* band, const std::string& file) {
  const GDALColorTable* table = band->GetColorTable();
  if (!table) throw Error(file + ": palette image without a colour table");
  const int w = band->GetXSize(), h = band->GetYSize();
  cv::Mat index(h, w, CV_8UC1);
  if (band->RasterIO(GF_Read, 0, 0, w, h, index.data, w, h, GDT_Byte, 1,
                     static_cast<GSpacing>(index.step), nullptr) != CE_None) {
    throw Error(file + ": cannot decode image" + QuietGdalErrors::Detail());
  }
  cv::Vec3b lut[256] = {};
  for (int i = 0; i < std::min(256, table->GetColorEntryCount()); ++i) {
    const GDALColorEntry* c = table->GetColorEntry(i);
    lut[i] =
        cv::Vec3b(static_cast<uchar>(c->c3), static_cast<uchar>(c->c2), static_cast<uchar>(c->c1));
  }
  cv::Mat out(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r) {
    const uchar* in = index.ptr<uchar>(r);
    cv::Vec3b* o = out.ptr<cv::Vec3b>(r);
    for (int c = 0; c < w; ++c) o[c] = lut[in[c]];
  }
  return out;
}

}  // namespace

cv::Mat DecodeImageWithGdal(const std::filesystem::path& path) {
  RegisterAllGdalDrivers();
  const std::string file = path.string();
  QuietGdalErrors quiet;
  DatasetPtr ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds || ds->GetRasterCount() < 1) {
    throw Error(file + ": cannot decode image" + quiet.Detail() +
                " (expected TIFF, JPEG, PNG, PPM/PGM, BMP or JPEG 2000)");
  }
  GDALRasterBand* first = ds->GetRasterBand(1);
  const GDALDataType type = first->GetRasterDataType();
  if (type != GDT_Byte && type != GDT_UInt16) {
    throw Error(file + ": " + GDALGetDataTypeName(type) +
                " samples, expected 8-bit or 16-bit unsigned integers");
  }
  if (first->GetColorInterpretation() == GCI_PaletteIndex && type == GDT_Byte) {
    return ExpandPalette(first, file);
  }
  const int w = ds->GetRasterXSize(), h = ds->GetRasterYSize();
  // OpenCV's order: blue, green, red; grey (with or without alpha) thrice.
  int bands[4] = {3, 2, 1, 4};
  if (ds->GetRasterCount() < 3) bands[0] = bands[1] = bands[2] = 1;
  const bool wide = type == GDT_UInt16;
  cv::Mat pixels(h, w, wide ? CV_16UC3 : CV_8UC3);
  const GSpacing sample = wide ? 2 : 1;
  if (ds->RasterIO(GF_Read, 0, 0, w, h, pixels.data, w, h, type, 3, bands, 3 * sample,
                   static_cast<GSpacing>(pixels.step), sample, nullptr) != CE_None) {
    throw Error(file + ": cannot decode image" + quiet.Detail());
  }
  if (wide) pixels.convertTo(pixels, CV_8U, 1.0 / 256.0);
  return pixels;
}

std::vector<unsigned char> EncodeImage(const cv::Mat& image, ImageEncoding encoding,
                                       const std::string& what, int jpeg_quality) {
  if (image.empty() ||
      (image.type() != CV_8UC3 && image.type() != CV_8UC1 && image.type() != CV_8UC4)) {
    throw Error(what + ": cannot encode image (expected 8-bit BGR, BGRA or grey pixels)");
  }
  GDALDriver* mem = GdalDriver("MEM");
  GDALDriver* driver = GdalDriver(DriverName(encoding));
  if (!mem || !driver) {
    throw Error(what + ": cannot encode image (GDAL has no " + DriverName(encoding) + " driver)");
  }
  QuietGdalErrors quiet;
  const int n = image.channels();
  DatasetPtr src(mem->Create("", image.cols, image.rows, n, GDT_Byte, nullptr));
  int bands[4] = {3, 2, 1, 4};
  if (n == 1) bands[0] = 1;
  if (!src || src->RasterIO(GF_Write, 0, 0, image.cols, image.rows, const_cast<uchar*>(image.data),
                            image.cols, image.rows, GDT_Byte, n, bands, n,
                            static_cast<GSpacing>(image.step), 1, nullptr) != CE_None) {
    throw Error(what + ": cannot encode image" + quiet.Detail());
  }
  if (n >= 3) {
    src->GetRasterBand(1)->SetColorInterpretation(GCI_RedBand);
    src->GetRasterBand(2)->SetColorInterpretation(GCI_GreenBand);
    src->GetRasterBand(3)->SetColorInterpretation(GCI_BlueBand);
  }
  if (n == 4) src->GetRasterBand(4)->SetColorInterpretation(GCI_AlphaBand);
  // Encoded in GDAL's in-memory file system; the name is unique per call so
  // threads encoding at once do not share a file.
  static std::atomic<unsigned long> serial{0};
  const std::string name = "/vsimem/sapmvs_encode_" + std::to_string(serial++);
  const std::string quality = "QUALITY=" + std::to_string(jpeg_quality);
  char* jpeg_options[] = {const_cast<char*>(quality.c_str()), nullptr};
  char* tiff_options[] = {const_cast<char*>("COMPRESS=LZW"), nullptr};
  char** options = encoding == ImageEncoding::kJpeg   ? jpeg_options
                   : encoding == ImageEncoding::kTiff ? tiff_options
                                                      : nullptr;
  DatasetPtr out(driver->CreateCopy(name.c_str(), src.get(), FALSE, options, nullptr, nullptr));
  const bool written = out != nullptr;
  out.reset();  // closing writes the last of the file
  VSIUnlink((name + ".aux.xml").c_str());
  vsi_l_offset length = 0;
  GByte* data = VSIGetMemFileBuffer(name.c_str(), &length, TRUE);
  std::vector<unsigned char> bytes(data, data + (data ? length : 0));
  CPLFree(data);
  if (!written || bytes.empty() || QuietGdalErrors::Failed()) {
    throw Error(what + ": cannot encode image as " + DriverName(encoding) + quiet.Detail());
  }
  return bytes;
}

cv::Size ReadImageSizeWithGdal(const std::filesystem::path& path) {
  RegisterAllGdalDrivers();
  const std::string file = path.string();
  QuietGdalErrors quiet;
  DatasetPtr ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) {
    const std::string detail = CPLGetLastErrorMsg();
    throw Error(file + ": not a readable image" +
                (detail.empty()
                     ? std::string(" (expected TIFF, JPEG, PNG, PPM/PGM, BMP or JPEG 2000)")
                     : " (" + detail + ")"));
  }
  return {ds->GetRasterXSize(), ds->GetRasterYSize()};
}

bool CanEncode(ImageEncoding encoding) { return GdalDriver(DriverName(encoding)) != nullptr; }

}  // namespace sapmvs

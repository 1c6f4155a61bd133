#pragma once
// Image files to and from pixels as OpenCV lays them out (8-bit, BGR or grey).
// JPEG and PNG are decoded with libjpeg-turbo and libpng, everything else read
// and written through GDAL's drivers, in the GDAL module (cli/gdal_module.h), so
// that a run on JPEG or PNG images loads GDAL only to write its rasters.
// OpenCV's own codecs (imgcodecs) are not linked: as Debian builds them they
// load GDAL besides, and a dozen more codecs' libraries (OpenEXR, DICOM, HEIF).

#include <filesystem>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace sapmvs {

enum class ImageEncoding { kPng, kJpeg, kTiff, kBmp, kPpm };

// The file's pixels as 8-bit BGR (the format found from the file's first
// bytes, not its name): grey is repeated in the three channels,
// 16-bit samples are scaled to 8 bits, alpha is dropped, a palette is
// expanded. The file's own orientation tags are not applied, so the pixels
// keep the sensor's layout that the camera's calibration refers to. Throws
// sapmvs::Error naming the file when it cannot be decoded or its samples are
// neither 8- nor 16-bit integers.
cv::Mat DecodeImageFile(const std::filesystem::path& path);

// Whether DecodeImageFile decodes the file without GDAL (JPEG, PNG; from
// its first bytes). False for a file it cannot read.
bool DecodedWithoutGdal(const std::filesystem::path& path);

// Width and height from the file's header.
cv::Size ReadImageFileSize(const std::filesystem::path& path);

// The bytes of `image` (CV_8UC3 in BGR order, CV_8UC4 in BGRA order, PNG
// and TIFF only, or CV_8UC1) as a file of the encoding; `jpeg_quality` (1-100) applies to JPEG
// only. The formats are lossless except JPEG. Throws sapmvs::Error naming `what` on failure.
std::vector<unsigned char> EncodeImage(const cv::Mat& image, ImageEncoding encoding,
                                       const std::string& what, int jpeg_quality = 95);

// Whether GDAL on this machine has the driver that writes the encoding.
bool CanEncode(ImageEncoding encoding);

}  // namespace sapmvs

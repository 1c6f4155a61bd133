#pragma once
// The image files the binary's own decoders (image_codec.cc) leave to GDAL:
// TIFF, BMP, PNM, JPEG 2000 and CMYK JPEG. GDAL code, in the GDAL module
// (cli/gdal_module.h).

#include <filesystem>
#include <opencv2/core/mat.hpp>

namespace sapmvs {

// As DecodeImageFile (image_codec.h).
cv::Mat DecodeImageWithGdal(const std::filesystem::path& path);
// Width and height; throws naming the file when GDAL cannot read it.
cv::Size ReadImageSizeWithGdal(const std::filesystem::path& path);

}  // namespace sapmvs

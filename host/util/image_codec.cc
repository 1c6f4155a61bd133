#include "util/image_codec.h"

#include <png.h>
#include <stdio.h>
// clang-format off: jpeglib.h needs stdio.h's FILE first.
#include <jpeglib.h>
// clang-format on

#include <cerrno>
#include <csetjmp>
#include <cstring>
#include <fstream>
#include <opencv2/core.hpp>
#include <vector>

#include "sapmvs/util/error.h"
#include "util/gdal_image_files.h"

namespace sapmvs {
namespace {

// JPEG and PNG, the formats of UAV cameras and of the simulator, are decoded
// here with libjpeg-turbo and libpng, so that a run on them never loads GDAL
// (cli/gdal_module.h); the rest goes through GDAL's drivers.
enum class Format { kJpeg, kPng, kOther };

Format Sniff(const std::filesystem::path& path) {
  unsigned char head[8] = {};
  std::ifstream in(path, std::ios::binary);
  in.read(reinterpret_cast<char*>(head), sizeof(head));
  if (in.gcount() >= 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF) {
    return Format::kJpeg;
  }
  if (in.gcount() == 8 && png_sig_cmp(head, 0, 8) == 0) return Format::kPng;
  return Format::kOther;
}

// Closes the file on every way out, longjmp included (it is a plain pointer
// set before setjmp).
struct File {
  explicit File(const std::filesystem::path& path) : f(std::fopen(path.c_str(), "rb")) {
    if (!f) {
      throw Error(path.string() + ": cannot open image (" + std::strerror(errno) + ")");
    }
  }
  ~File() { std::fclose(f); }
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  FILE* f;
};

struct JpegError {
  jpeg_error_mgr manager;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void OnJpegError(j_common_ptr info) {
  auto* e = reinterpret_cast<JpegError*>(info->err);
  (*info->err->format_message)(info, e->message);
  std::longjmp(e->jump, 1);
}

// Corrupt data is a warning to libjpeg, which then decodes what it can;
// OpenCV and GDAL accept such files as well. A truncated file is refused
// before (image_io.cc).
void IgnoreJpegMessage(j_common_ptr /*info*/, int /*level*/) {}

enum class Decoded { kDone, kFailed, kNotHere };

// Decodes into `pixels` (8-bit BGR) or, when `pixels` is null, reads the size
// only. No C++ object with a destructor lives between setjmp and longjmp.
Decoded DecodeJpeg(FILE* f, cv::Mat* pixels, cv::Size* size, std::string* error) {
  jpeg_decompress_struct info;
  JpegError err;
  info.err = jpeg_std_error(&err.manager);
  err.manager.error_exit = OnJpegError;
  err.manager.emit_message = IgnoreJpegMessage;
  if (setjmp(err.jump)) {
    jpeg_destroy_decompress(&info);
    *error = err.message;
    return Decoded::kFailed;
  }
  jpeg_create_decompress(&info);
  jpeg_stdio_src(&info, f);
  jpeg_read_header(&info, TRUE);
  *size = cv::Size(static_cast<int>(info.image_width), static_cast<int>(info.image_height));
  // libjpeg cannot turn CMYK into RGB; GDAL can.
  const bool cmyk = info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK;
  if (!pixels || cmyk) {
    jpeg_destroy_decompress(&info);
    return pixels ? Decoded::kNotHere : Decoded::kDone;
  }
  info.out_color_space = JCS_EXT_BGR;
  jpeg_start_decompress(&info);
  pixels->create(size->height, size->width, CV_8UC3);
  while (info.output_scanline < info.output_height) {
    JSAMPROW row = pixels->ptr<JSAMPLE>(static_cast<int>(info.output_scanline));
    jpeg_read_scanlines(&info, &row, 1);
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return Decoded::kDone;
}

struct PngError {
  char message[256];
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* e = static_cast<PngError*>(png_get_error_ptr(png));
  std::snprintf(e->message, sizeof(e->message), "%s", message);
  png_longjmp(png, 1);
}

void IgnorePngWarning(png_structp /*png*/, png_const_charp /*message*/) {}

// As DecodeJpeg; `rows` is the caller's, so that a longjmp passes no
// destructor. The transformations give what OpenCV's imread gave: 16-bit
// samples keep their high byte, a palette and low bit depths are expanded,
// grey is repeated, alpha dropped, no gamma applied.
Decoded DecodePng(FILE* f, cv::Mat* pixels, cv::Size* size, std::string* error,
                  std::vector<png_bytep>* rows) {
  PngError err{};
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, &err, OnPngError, IgnorePngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    *error = "out of memory";
    return Decoded::kFailed;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    *error = err.message;
    return Decoded::kFailed;
  }
  png_init_io(png, f);
  png_read_info(png, info);
  *size = cv::Size(static_cast<int>(png_get_image_width(png, info)),
                   static_cast<int>(png_get_image_height(png, info)));
  if (!pixels) {
    png_destroy_read_struct(&png, &info, nullptr);
    return Decoded::kDone;
  }
  const int type = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (depth == 16) png_set_strip_16(png);
  if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  if (type == PNG_COLOR_TYPE_GRAY || type == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png);
  png_set_bgr(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  pixels->create(size->height, size->width, CV_8UC3);
  rows->resize(static_cast<size_t>(size->height));
  for (int r = 0; r < size->height; ++r) (*rows)[static_cast<size_t>(r)] = pixels->ptr<png_byte>(r);
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return Decoded::kDone;
}

// Decodes (pixels non-null) or reads the size; false when GDAL is to.
bool DecodeHere(const std::filesystem::path& path, cv::Mat* pixels, cv::Size* size) {
  const Format format = Sniff(path);
  if (format == Format::kOther) return false;
  File file(path);
  std::string error;
  std::vector<png_bytep> rows;
  const Decoded d = format == Format::kJpeg ? DecodeJpeg(file.f, pixels, size, &error)
                                            : DecodePng(file.f, pixels, size, &error, &rows);
  if (d == Decoded::kFailed) {
    throw Error(path.string() + ": cannot decode image (" +
                (format == Format::kJpeg ? "libjpeg: " : "libpng: ") + error + ")");
  }
  return d == Decoded::kDone;
}

}  // namespace

cv::Mat DecodeImageFile(const std::filesystem::path& path) {
  cv::Mat pixels;
  cv::Size size;
  if (DecodeHere(path, &pixels, &size)) return pixels;
  return DecodeImageWithGdal(path);
}

bool DecodedWithoutGdal(const std::filesystem::path& path) { return Sniff(path) != Format::kOther; }

cv::Size ReadImageFileSize(const std::filesystem::path& path) {
  cv::Size size;
  if (DecodeHere(path, nullptr, &size)) return size;
  return ReadImageSizeWithGdal(path);
}

}  // namespace sapmvs

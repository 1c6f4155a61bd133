#pragma once
// GDAL and the hundred libraries it loads (PROJ, GEOS, HDF5, poppler, ...)
// are mapped into the binary only when a step needs them. Their start-up alone
// keeps about 25 MiB resident, and at the peak of a run on a 18-image block
// they held 36 of its 231 MiB, for images that libjpeg and libpng decode and a
// DSM written once at the end. So the code that calls GDAL (the files in
// host/CMakeLists.txt's SAPMVS_GDAL_SOURCES) is linked into a module,
// libsapmvs_gdal.so, beside the binary or in ../lib/sapmvs, and loaded on the
// first call of one of its functions; the binary defines those functions as
// calls through this table (gdal_module.cc). Tests and tools link the same
// code directly (sapmvs_core).

#include <filesystem>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "block/ecef_to_utm.h"
#include "sapmvs/block/dem.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/dsm_picture.h"
#include "util/image_codec.h"

namespace sapmvs {

struct GdalModuleFunctions {
  // A module from another build is refused: the table's layout is checked
  // by its size and this number, raised with every change to it.
  int version = 0;
  size_t size = 0;
  cv::Mat (*decode_image)(const std::filesystem::path&);
  cv::Size (*read_image_size)(const std::filesystem::path&);
  std::vector<unsigned char> (*encode_image)(const cv::Mat&, ImageEncoding, const std::string&,
                                             int);
  bool (*can_encode)(ImageEncoding);
  Dem (*load_dem)(const std::filesystem::path&, long);
  std::unique_ptr<EcefToUtm> (*make_ecef_to_utm)(int);
  void (*write_geotiff)(const std::filesystem::path&, const GeoRaster&);
  void (*write_color_geotiff)(const std::filesystem::path&, const GeoRaster&,
                              const std::vector<uint8_t>&);
  GeoRaster (*read_geo_raster)(const std::filesystem::path&);
  std::string (*crs_to_wkt)(const std::string&);
  CrsIdentity (*identify_crs)(const std::string&);
  WktFacts (*read_wkt_facts)(const std::string&);
  std::string (*crs_linear_unit)(const std::string&);
  DsmPictures (*write_dsm_pictures)(const GeoRaster&, const std::filesystem::path&,
                                    const std::filesystem::path&, const DsmPictureOptions&);
};

constexpr int kGdalModuleVersion = 2;

// The argument that makes the binary a CRS checker (GeoOutputsCheck in
// gdal_module.cc): `sapmvs --internal-check-crs CRS` loads the module, checks
// CRS, prints what is wrong on stderr and exits 1, or exits 0.
constexpr const char* kCheckCrsArgument = "--internal-check-crs";
int CheckCrsMain(const char* crs);

}  // namespace sapmvs

// The module's one entry point: registers GDAL's drivers and our message
// handler (util/gdal_messages.h) once, and returns the table.
extern "C" const sapmvs::GdalModuleFunctions* sapmvs_gdal_module();

// The GDAL module's entry point (gdal_module.h). The module is linked with
// -Bsymbolic, so the addresses taken here are the module's own functions and
// not the binary's same-named calls through the table.
#include <gdal_priv.h>

#include "cli/gdal_module.h"
#include "util/gdal_image_files.h"
#include "util/gdal_messages.h"

extern "C" __attribute__((visibility("default"))) const sapmvs::GdalModuleFunctions*
sapmvs_gdal_module() {
  using namespace sapmvs;
  static const GdalModuleFunctions table = [] {
    // No drivers here: each function registers those it needs
    // (util/gdal_drivers.h), so that writing the outputs does not register
    // every driver.
    // GDAL's warnings become detail lines, its failures part of our messages.
    InstallGdalMessageHandler();
    GdalModuleFunctions t;
    t.version = kGdalModuleVersion;
    t.size = sizeof(GdalModuleFunctions);
    t.decode_image = &DecodeImageWithGdal;
    t.read_image_size = &ReadImageSizeWithGdal;
    t.encode_image = &EncodeImage;
    t.can_encode = &CanEncode;
    t.load_dem = &Dem::Load;
    t.make_ecef_to_utm = &MakeEcefToUtm;
    t.write_geotiff = &WriteGeoTiff;
    t.write_color_geotiff = &WriteColorGeoTiff;
    t.read_geo_raster = &ReadGeoRaster;
    t.crs_to_wkt = &CrsToWkt;
    t.identify_crs = &IdentifyCrs;
    t.read_wkt_facts = &ReadWktFacts;
    t.crs_linear_unit = &CrsLinearUnit;
    t.write_dsm_pictures = &WriteDsmPictures;
    return t;
  }();
  return &table;
}

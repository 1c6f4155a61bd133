#pragma once
// GDAL's drivers, registered as each step needs them. GDALAllRegister runs the
// registration of every driver GDAL was built with (over 200 on Debian), which
// touches code all through libgdal: writing a GeoTIFF after it took a process
// 7 MiB more resident memory than after registering GTiff alone. A run's
// outputs need four drivers (GTiff and COG, PNG, MEM); reading what users bring
// (images, DEMs, rasters of any format) needs them all.
#include <string>

class GDALDriver;

namespace sapmvs {

// Every driver, once per process. Thread-safe, as GdalDriver.
void RegisterAllGdalDrivers();

// One driver GDAL builds in, registered first: "GTiff", "COG", "PNG",
// "JPEG", "MEM", "PNM" or "BMP"; nullptr when this GDAL was built without it.
// Throws Error for another name (a programming error: the others are only
// reached through RegisterAllGdalDrivers). Registering twice is harmless.
GDALDriver* GdalDriver(const std::string& name);

}  // namespace sapmvs

#include "util/gdal_drivers.h"

#include <gdal_frmts.h>
#include <gdal_priv.h>

#include <mutex>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// GDAL's registration functions return early for a driver that is there,
// but two threads may both find it missing; one lock serialises all of ours.
std::mutex& RegistrationMutex() {
  static std::mutex m;
  return m;
}

}  // namespace

void RegisterAllGdalDrivers() {
  static bool all = false;
  std::lock_guard<std::mutex> lock(RegistrationMutex());
  if (all) return;
  GDALAllRegister();
  all = true;
}

GDALDriver* GdalDriver(const std::string& name) {
  void (*reg)() = nullptr;
  if (name == "GTiff") reg = &GDALRegister_GTiff;
  if (name == "PNG") reg = &GDALRegister_PNG;
  if (name == "JPEG") reg = &GDALRegister_JPEG;
  if (name == "MEM") reg = &GDALRegister_MEM;
  if (name == "PNM") reg = &GDALRegister_PNM;
  if (name == "BMP") reg = &GDALRegister_BMP;
  if (name == "COG") reg = &GDALRegister_COG;
  if (!reg) throw Error("GdalDriver: no built-in GDAL driver '" + name + "'");
  std::lock_guard<std::mutex> lock(RegistrationMutex());
  reg();
  return GetGDALDriverManager()->GetDriverByName(name.c_str());
}

}  // namespace sapmvs

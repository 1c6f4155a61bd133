#include "sapmvs/io/raster_io.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <sstream>
#include <utility>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "util/gdal_drivers.h"
#include "util/gdal_messages.h"

namespace sapmvs {
namespace {

void CheckRaster(const std::filesystem::path& path, const GeoRaster& r) {
  const std::string file = path.string();
  if (r.width <= 0 || r.height <= 0) {
    throw Error(file + ": raster size " + std::to_string(r.width) + " x " +
                std::to_string(r.height) + " (expected positive width and height)");
  }
  if (r.values.size() != static_cast<size_t>(r.width) * r.height) {
    throw Error(file + ": raster has " + std::to_string(r.values.size()) + " values, expected " +
                std::to_string(r.width) + " x " + std::to_string(r.height));
  }
  if (!(r.cell_size > 0) || !std::isfinite(r.cell_size)) {
    throw Error(file + ": cell size " + FormatNumber(r.cell_size, 12) +
                " (expected a positive number)");
  }
  if (!std::isfinite(r.origin_x) || !std::isfinite(r.origin_y)) {
    throw Error(file + ": raster origin (" + FormatNumber(r.origin_x, 12) + ", " +
                FormatNumber(r.origin_y, 12) + ") (expected finite coordinates)");
  }
}

// The raster in memory, then copied by the COG driver: a Cloud-Optimized
// GeoTIFF, tiled, with overviews, which GIS and web viewers read in parts.
// The COG driver writes only copies of a whole dataset.
void WriteCog(const std::string& file, const std::filesystem::path& tmp, GDALDataset* mem,
              const GeoRaster& grid, const OGRSpatialReference* srs, QuietGdalErrors& quiet) {
  double geo[6] = {grid.origin_x, grid.cell_size, 0, grid.origin_y, 0, -grid.cell_size};
  if (mem->SetGeoTransform(geo) != CE_None || (srs && mem->SetSpatialRef(srs) != CE_None)) {
    throw Error(file + ": cannot write GeoTIFF" + quiet.Detail());
  }
  GDALDriver* cog = GdalDriver("COG");
  if (!GdalDriver("GTiff")) throw Error(file + ": GDAL has no GTiff driver");  // COG's writer
  if (!cog) throw Error(file + ": GDAL has no COG driver");
  CPLStringList options;
  options.SetNameValue("COMPRESS", "DEFLATE");
  options.SetNameValue("PREDICTOR", "YES");  // floating point or horizontal, as the type wants
  options.SetNameValue("BLOCKSIZE", "256");
  options.SetNameValue("BIGTIFF", "IF_SAFER");
  // Averages keep an overview's heights and colours those of its cells.
  options.SetNameValue("RESAMPLING", "AVERAGE");
  CPLErrorReset();
  DatasetPtr ds(
      cog->CreateCopy(tmp.string().c_str(), mem, FALSE, options.List(), nullptr, nullptr));
  if (!ds) throw Error(file + ": cannot write GeoTIFF" + quiet.Detail());
  // The directory is written on close, where a full disk shows up.
  ds.reset();
  if (QuietGdalErrors::Failed()) throw Error(file + ": cannot write GeoTIFF" + quiet.Detail());
}

DatasetPtr MemDataset(const std::string& file, int width, int height, int bands, GDALDataType type,
                      QuietGdalErrors& quiet) {
  GDALDriver* driver = GdalDriver("MEM");
  if (!driver) throw Error(file + ": GDAL has no MEM driver");
  DatasetPtr mem(driver->Create("", width, height, bands, type, nullptr));
  if (!mem) throw Error(file + ": cannot create GeoTIFF" + quiet.Detail());
  return mem;
}

// A MEM band over `data` itself (MEM's DATAPOINTER): the copy for the COG
// driver would double what a large orthophoto holds.
void AddBandOver(const std::string& file, GDALDataset* mem, GDALDataType type, const void* data,
                 int pixel_offset, long line_offset, QuietGdalErrors& quiet) {
  char pointer[64];
  std::snprintf(pointer, sizeof pointer, "%p", data);
  CPLStringList options;
  options.SetNameValue("DATAPOINTER", pointer);
  options.SetNameValue("PIXELOFFSET", std::to_string(pixel_offset).c_str());
  options.SetNameValue("LINEOFFSET", std::to_string(line_offset).c_str());
  if (mem->AddBand(type, options.List()) != CE_None) {
    throw Error(file + ": cannot write GeoTIFF" + quiet.Detail());
  }
}

void WriteTiff(const std::string& file, const std::filesystem::path& tmp, const GeoRaster& raster,
               const OGRSpatialReference* srs) {
  QuietGdalErrors quiet;
  DatasetPtr mem = MemDataset(file, raster.width, raster.height, 0, GDT_Float32, quiet);
  AddBandOver(file, mem.get(), GDT_Float32, raster.values.data(), 4, 4L * raster.width, quiet);
  if (mem->GetRasterBand(1)->SetNoDataValue(raster.nodata) != CE_None) {
    throw Error(file + ": cannot write GeoTIFF" + quiet.Detail());
  }
  WriteCog(file, tmp, mem.get(), raster, srs, quiet);
}

// RGBA, 8 bit, interleaved per pixel, on `grid`'s geotransform: photometric
// RGB with an alpha band, so GIS shows nodata as transparent.
void WriteRgbaTiff(const std::string& file, const std::filesystem::path& tmp, const GeoRaster& grid,
                   const OGRSpatialReference* srs, const std::vector<uint8_t>& rgba) {
  QuietGdalErrors quiet;
  DatasetPtr mem = MemDataset(file, grid.width, grid.height, 0, GDT_Byte, quiet);
  const GDALColorInterp interp[4] = {GCI_RedBand, GCI_GreenBand, GCI_BlueBand, GCI_AlphaBand};
  for (int b = 0; b < 4; ++b) {
    AddBandOver(file, mem.get(), GDT_Byte, rgba.data() + b, 4, 4L * grid.width, quiet);
    mem->GetRasterBand(b + 1)->SetColorInterpretation(interp[b]);
  }
  WriteCog(file, tmp, mem.get(), grid, srs, quiet);
}

OGRSpatialReference SpatialRefOf(const std::filesystem::path& path, const std::string& crs) {
  OGRSpatialReference srs;
  if (!crs.empty()) {
    try {
      srs.importFromWkt(CrsToWkt(crs).c_str());
    } catch (const Error& e) {
      throw Error(path.string() + ": " + e.what());
    }
  }
  return srs;
}

// Runs `write(tmp)` and commits the file. GDAL keeps what GeoTIFF tags cannot
// hold (a CRS without GeoTIFF keys) in a side-car beside the file it wrote.
// It must follow the rename, and a stale one left by an earlier file at
// `path` must not describe this one.
void CommitTiff(const std::filesystem::path& path,
                const std::function<void(const std::filesystem::path& tmp)>& write) {
  AtomicFile out(path);
  const std::filesystem::path temp_aux = out.temp_path().string() + ".aux.xml";
  const std::filesystem::path aux = path.string() + ".aux.xml";
  std::error_code ec;
  try {
    write(out.temp_path());
    out.Commit();
  } catch (...) {
    std::filesystem::remove(temp_aux, ec);
    throw;
  }
  if (std::filesystem::exists(temp_aux, ec)) {
    std::filesystem::rename(temp_aux, aux, ec);
    if (ec) throw Error(aux.string() + ": cannot write GDAL side-car (" + ec.message() + ")");
  } else {
    std::filesystem::remove(aux, ec);
  }
}

}  // namespace

std::string CrsToWkt(const std::string& crs) {
  if (crs.empty()) return "";
  QuietGdalErrors quiet;
  OGRSpatialReference srs;
  const char* const options[] = {"ALLOW_NETWORK_ACCESS=NO", nullptr};
  if (srs.SetFromUserInput(crs.c_str(), options) != OGRERR_NONE) {
    throw Error("CRS '" + crs + "': expected WKT, EPSG:n or a PROJ string" + quiet.Detail());
  }
  char* wkt = nullptr;
  const OGRErr err = srs.exportToWkt(&wkt);
  const std::string out = wkt ? wkt : "";
  CPLFree(wkt);
  if (err != OGRERR_NONE || out.empty()) {
    throw Error("CRS '" + crs + "': cannot be written as WKT" + quiet.Detail());
  }
  return out;
}

// GDAL is linked in here (tests, tools): the check needs no process.
GeoOutputsCheck::GeoOutputsCheck(std::string crs, std::string source)
    : crs_(std::move(crs)), source_(std::move(source)) {}

GeoOutputsCheck::~GeoOutputsCheck() = default;

void GeoOutputsCheck::Wait() {
  try {
    CrsToWkt(crs_);
  } catch (const Error& e) {
    throw Error(source_ + ": " + e.what());
  }
}

double GdalBytesToLoad() { return 0; }

CrsIdentity IdentifyCrs(const std::string& crs) {
  QuietGdalErrors quiet;
  OGRSpatialReference srs;
  const char* const options[] = {"ALLOW_NETWORK_ACCESS=NO", nullptr};
  if (crs.empty() || srs.SetFromUserInput(crs.c_str(), options) != OGRERR_NONE) {
    throw Error("CRS '" + crs + "': expected WKT, EPSG:n or a PROJ string" + quiet.Detail());
  }
  CrsIdentity id;
  if (const char* name = srs.GetName()) id.name = name;
  // A WKT without an AUTHORITY node may still be an EPSG CRS by content.
  const char* authority = srs.GetAuthorityName(nullptr);
  if (!(authority && EQUAL(authority, "EPSG"))) {
    srs.AutoIdentifyEPSG();
    authority = srs.GetAuthorityName(nullptr);
  }
  const char* code = srs.GetAuthorityCode(nullptr);
  if (authority && EQUAL(authority, "EPSG") && code) id.epsg = std::atoi(code);
  return id;
}

void WriteGeoTiff(const std::filesystem::path& path, const GeoRaster& raster) {
  CheckRaster(path, raster);
  const OGRSpatialReference srs = SpatialRefOf(path, raster.crs);
  CommitTiff(path, [&](const std::filesystem::path& tmp) {
    WriteTiff(path.string(), tmp, raster, raster.crs.empty() ? nullptr : &srs);
  });
}

void WriteColorGeoTiff(const std::filesystem::path& path, const GeoRaster& grid,
                       const std::vector<uint8_t>& rgba) {
  GeoRaster shape = grid;
  shape.values.assign(static_cast<size_t>(std::max(0, grid.width)) * std::max(0, grid.height), 0);
  CheckRaster(path, shape);
  if (rgba.size() != 4 * shape.values.size()) {
    throw Error(path.string() + ": " + std::to_string(rgba.size()) + " RGBA bytes for " +
                std::to_string(grid.width) + " x " + std::to_string(grid.height) +
                " pixels (expected 4 per pixel)");
  }
  const OGRSpatialReference srs = SpatialRefOf(path, grid.crs);
  CommitTiff(path, [&](const std::filesystem::path& tmp) {
    WriteRgbaTiff(path.string(), tmp, grid, grid.crs.empty() ? nullptr : &srs, rgba);
  });
}

WktFacts ReadWktFacts(const std::string& wkt) {
  WktFacts facts;
  OGRSpatialReference srs;
  if (wkt.empty() || srs.importFromWkt(wkt.c_str()) != OGRERR_NONE) return facts;
  facts.projected = srs.IsProjected();
  facts.geographic = srs.IsGeographic();
  auto code = [&](const char* node) -> int {
    const char* authority = srs.GetAuthorityName(node);
    const char* c = srs.GetAuthorityCode(node);
    return authority && c && std::strcmp(authority, "EPSG") == 0 ? std::atoi(c) : 0;
  };
  const char* horizontal = facts.projected ? "PROJCS" : facts.geographic ? "GEOGCS" : nullptr;
  if (horizontal) facts.horizontal_epsg = code(horizontal);
  facts.vertical_epsg = code("VERT_CS");
  return facts;
}

std::string CrsLinearUnit(const std::string& crs) {
  if (crs.empty()) return "";
  OGRSpatialReference srs;
  try {
    if (srs.importFromWkt(CrsToWkt(crs).c_str()) != OGRERR_NONE) return "";
  } catch (const Error&) {
    return "";
  }
  if (srs.IsGeographic()) return "deg";
  if (!srs.IsProjected() && !srs.IsLocal()) return "";
  const char* name = nullptr;
  const double to_metre = srs.GetLinearUnits(&name);
  if (std::abs(to_metre - 1) < 1e-12) return "m";
  if (std::abs(to_metre - 0.3048) < 1e-12) return "ft";
  if (std::abs(to_metre - 1200.0 / 3937.0) < 1e-12) return "ftUS";
  return name ? name : "";
}

GeoRaster ReadGeoRaster(const std::filesystem::path& path) {
  const std::string file = path.string();
  RegisterAllGdalDrivers();
  QuietGdalErrors quiet;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error(file + ": cannot open raster (missing or not a file)");
  }
  DatasetPtr ds(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds)
    throw InputError(file, 0,
                     "not a raster GDAL can read (expected GeoTIFF or another GDAL raster format)" +
                         quiet.Detail());
  if (ds->GetRasterCount() < 1) throw InputError(file, 0, "expected at least one band, got none");
  GeoRaster r;
  r.width = ds->GetRasterXSize();
  r.height = ds->GetRasterYSize();
  double geo[6];
  if (ds->GetGeoTransform(geo) != CE_None) {
    throw InputError(file, 0, "expected a georeferenced raster (no geotransform)");
  }
  if (geo[2] != 0 || geo[4] != 0) {
    throw InputError(file, 0, "expected a north-up raster, got a rotated geotransform");
  }
  const double dx = geo[1], dy = std::abs(geo[5]);
  if (!(dx > 0) || !(dy > 0) || std::abs(dx - dy) > 1e-9 * dx) {
    throw InputError(file, 0,
                     "expected square cells with columns running east, got cell size " +
                         FormatNumber(dx, 12) + " x " + FormatNumber(geo[5], 12));
  }
  const bool south_up = geo[5] > 0;
  r.cell_size = dx;
  r.origin_x = geo[0];
  r.origin_y = south_up ? geo[3] + r.height * geo[5] : geo[3];

  GDALRasterBand* band = ds->GetRasterBand(1);
  r.values.resize(static_cast<size_t>(r.width) * r.height);
  if (band->RasterIO(GF_Read, 0, 0, r.width, r.height, r.values.data(), r.width, r.height,
                     GDT_Float32, 0, 0) != CE_None) {
    throw InputError(file, 0, "cannot read the values of band 1" + quiet.Detail());
  }
  if (south_up) {
    for (int row = 0; row < r.height / 2; ++row) {
      std::swap_ranges(&r.at(0, row), &r.at(0, row) + r.width, &r.at(0, r.height - 1 - row));
    }
  }
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  if (has_nodata) r.nodata = static_cast<float>(nodata);

  if (const OGRSpatialReference* srs = ds->GetSpatialRef()) {
    char* wkt = nullptr;
    if (srs->exportToWkt(&wkt) == OGRERR_NONE && wkt) r.crs = wkt;
    CPLFree(wkt);
  }
  return r;
}

}  // namespace sapmvs

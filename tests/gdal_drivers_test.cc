// GDAL's drivers are registered as each step needs them: writing a run's
// outputs registers the four it writes with, reading what users bring
// registers them all.
#include "util/gdal_drivers.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/dsm_picture.h"
#include "sapmvs/util/error.h"
#include "test_util.h"
#include "util/gdal_image_files.h"

namespace sapmvs {
namespace {

class GdalDriversTest : public test::ScratchTest {};

// In a process of its own (a death test in the "threadsafe" style runs the
// test binary again for this one test), so that no earlier test has
// registered any driver.
TEST_F(GdalDriversTest, OutputsRegisterTheirDriversAndReadersAll) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::filesystem::path dir = dir_;
  EXPECT_EXIT(
      {
        GeoRaster dsm;
        dsm.width = 23;
        dsm.height = 17;
        dsm.origin_x = 500000;
        dsm.origin_y = 5400000;
        dsm.cell_size = 0.5;
        dsm.crs = "EPSG:32632";
        dsm.values.resize(static_cast<size_t>(dsm.width) * dsm.height);
        for (size_t i = 0; i < dsm.values.size(); ++i) dsm.values[i] = 300.0f + 0.1f * (i % 23);
        const int before = GDALGetDriverCount();
        WriteGeoTiff(dir / "dsm.tif", dsm);
        WriteDsmPictures(dsm, dir / "dsm_color.tif", dir / "dsm.png");
        const int outputs = GDALGetDriverCount();
        const bool four = outputs == 4 && GDALGetDriverByName("GTiff") &&
                          GDALGetDriverByName("COG") && GDALGetDriverByName("PNG") &&
                          GDALGetDriverByName("MEM");
        DecodeImageWithGdal(dir / "dsm_color.tif");
        const int all = GDALGetDriverCount();
        std::fprintf(stderr, "drivers: %d before, %d after the outputs, %d after a read\n", before,
                     outputs, all);
        std::exit(before == 0 && four && all > 20 && GDALGetDriverByName("JPEG") ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "drivers: 0 before, 4 after the outputs");
}

TEST(GdalDrivers, OnlyBuiltInDriversByName) {
  GDALDriver* gtiff = GdalDriver("GTiff");
  EXPECT_NE(gtiff, nullptr);
  EXPECT_EQ(GdalDriver("GTiff"), gtiff);  // again: harmless
  EXPECT_EQ(GDALDriver::ToHandle(gtiff), GDALGetDriverByName("GTiff"));
  try {
    GdalDriver("HDF5");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'HDF5'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

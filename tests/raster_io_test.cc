#include "sapmvs/io/raster_io.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

class RasterIoTest : public test::ScratchTest {
 protected:
  void SetUp() override {
    ScratchTest::SetUp();
    GDALAllRegister();
  }
};

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(ds); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

// A UTM-like DSM with a nodata hole in every 7th cell.
GeoRaster RandomDsm(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> z(250, 350);
  GeoRaster r;
  r.width = width;
  r.height = height;
  r.origin_x = 500010.25;
  r.origin_y = 5400990.75;
  r.cell_size = 0.5;
  r.nodata = -9999;
  r.crs = "EPSG:32632";
  r.values.resize(static_cast<size_t>(width) * height);
  for (size_t i = 0; i < r.values.size(); ++i) r.values[i] = i % 7 == 3 ? r.nodata : z(rng);
  return r;
}

bool SameCrs(const std::string& wkt, const char* user_input) {
  OGRSpatialReference a, b;
  return a.importFromWkt(wkt.c_str()) == OGRERR_NONE &&
         b.SetFromUserInput(user_input) == OGRERR_NONE && a.IsSame(&b);
}

TEST_F(RasterIoTest, RoundTripKeepsValuesNodataAndCrsAtOddSizes) {
  for (const auto& [w, h] : {std::pair{7, 5}, std::pair{93, 31}, std::pair{1, 1}}) {
    SCOPED_TRACE(std::to_string(w) + " x " + std::to_string(h));
    const fs::path path = dir_ / ("dsm_" + std::to_string(w) + ".tif");
    const GeoRaster in = RandomDsm(w, h, static_cast<unsigned>(w * 100 + h));
    WriteGeoTiff(path, in);
    const GeoRaster out = ReadGeoRaster(path);
    EXPECT_EQ(out.width, w);
    EXPECT_EQ(out.height, h);
    EXPECT_EQ(out.origin_x, in.origin_x);
    EXPECT_EQ(out.origin_y, in.origin_y);
    EXPECT_EQ(out.cell_size, in.cell_size);
    EXPECT_EQ(out.nodata, in.nodata);
    EXPECT_EQ(out.values, in.values);
    EXPECT_TRUE(SameCrs(out.crs, "EPSG:32632")) << out.crs;
    if (w * h > 3) {
      EXPECT_TRUE(out.IsEmpty(3 % w, 3 / w));
    }
  }
}

TEST_F(RasterIoTest, NanNodataAndNoCrsRoundTrip) {
  const fs::path path = dir_ / "nan.tif";
  GeoRaster in = RandomDsm(7, 5, 1);
  in.nodata = std::numeric_limits<float>::quiet_NaN();
  in.crs.clear();
  in.at(2, 4) = in.nodata;
  WriteGeoTiff(path, in);
  const GeoRaster out = ReadGeoRaster(path);
  EXPECT_TRUE(std::isnan(out.nodata));
  EXPECT_TRUE(out.crs.empty()) << out.crs;
  EXPECT_TRUE(out.IsEmpty(2, 4));
  EXPECT_TRUE(std::isnan(out.at(2, 4)));
  EXPECT_EQ(out.at(1, 1), in.at(1, 1));
}

TEST_F(RasterIoTest, GdalSideCarOfACrsWithoutGeoTiffKeysFollowsTheFile) {
  const fs::path path = dir_ / "rotated_pole.tif";
  GeoRaster in = RandomDsm(7, 5, 5);
  in.crs = "+proj=ob_tran +o_proj=longlat +o_lon_p=10 +o_lat_p=40 +datum=WGS84";
  WriteGeoTiff(path, in);
  EXPECT_TRUE(fs::exists(path.string() + ".aux.xml"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2)
      << "no temporary side-car left behind";
  EXPECT_NE(ReadGeoRaster(path).crs.find("ob_tran"), std::string::npos);

  // A later file without a side-car must not inherit the stale one.
  in.crs = "EPSG:32632";
  WriteGeoTiff(path, in);
  EXPECT_FALSE(fs::exists(path.string() + ".aux.xml"));
  EXPECT_TRUE(SameCrs(ReadGeoRaster(path).crs, "EPSG:32632"));
}

TEST_F(RasterIoTest, GdalSeesTheSameGeotransformAndATiledDeflateFloat32) {
  const fs::path path = dir_ / "dsm.tif";
  const GeoRaster in = RandomDsm(93, 31, 2);
  WriteGeoTiff(path, in);
  Dataset ds(GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  ASSERT_TRUE(ds);
  EXPECT_STREQ(ds->GetDriver()->GetDescription(), "GTiff");
  double geo[6];
  ASSERT_EQ(ds->GetGeoTransform(geo), CE_None);
  const double expected[6] = {500010.25, 0.5, 0, 5400990.75, 0, -0.5};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(geo[i], expected[i]) << i;
  GDALRasterBand* band = ds->GetRasterBand(1);
  EXPECT_EQ(band->GetRasterDataType(), GDT_Float32);
  int bx = 0, by = 0;
  band->GetBlockSize(&bx, &by);
  EXPECT_EQ(bx, 256);
  EXPECT_EQ(by, 256);
  const char* compression = ds->GetMetadataItem("COMPRESSION", "IMAGE_STRUCTURE");
  ASSERT_NE(compression, nullptr);
  EXPECT_STREQ(compression, "DEFLATE");
  int has_nodata = 0;
  EXPECT_EQ(band->GetNoDataValue(&has_nodata), -9999);
  EXPECT_TRUE(has_nodata);
  float v = 0;
  ASSERT_EQ(band->RasterIO(GF_Read, 92, 30, 1, 1, &v, 1, 1, GDT_Float32, 0, 0), CE_None);
  EXPECT_EQ(v, in.at(92, 30));
}

TEST_F(RasterIoTest, CellCenterIsHalfACellInsideTheCorner) {
  GeoRaster r;
  r.origin_x = 100;
  r.origin_y = 200;
  r.cell_size = 2;
  EXPECT_EQ(r.CellCenter(0, 0), Eigen::Vector2d(101, 199));
  EXPECT_EQ(r.CellCenter(3, 1), Eigen::Vector2d(107, 197));
}

TEST_F(RasterIoTest, MissingDirectoryThrowsNamingThePathAndWritesNothing) {
  const fs::path path = dir_ / "missing" / "dsm.tif";
  try {
    WriteGeoTiff(path, RandomDsm(7, 5, 3));
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(DirIsEmpty());
}

TEST_F(RasterIoTest, InvalidRastersAreRefusedAndTheOldFileSurvives) {
  const fs::path path = dir_ / "dsm.tif";
  const GeoRaster good = RandomDsm(7, 5, 4);
  WriteGeoTiff(path, good);
  const auto size = fs::file_size(path);

  GeoRaster bad = good;
  bad.values.pop_back();
  EXPECT_THROW(WriteGeoTiff(path, bad), Error);
  bad = good;
  bad.cell_size = 0;
  EXPECT_THROW(WriteGeoTiff(path, bad), Error);
  bad = good;
  bad.crs = "EPSG:999999999";
  try {
    WriteGeoTiff(path, bad);
    FAIL() << "expected sapmvs::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("EPSG:999999999"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::file_size(path), size);
  EXPECT_EQ(ReadGeoRaster(path).values, good.values);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(RasterIoTest, UnreadableFilesAreErrorsNamingTheFile) {
  const fs::path text = dir_ / "notes.tif";
  std::ofstream(text) << "not a raster\n";
  try {
    ReadGeoRaster(text);
    FAIL() << "expected sapmvs::InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), text.string());
    EXPECT_NE(std::string(e.what()).find("not a raster GDAL can read"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ReadGeoRaster(dir_ / "missing.tif"), Error);
}

// Writes a 3 x 2 raster with GDAL directly, with the given geotransform.
void WriteWithGeotransform(const fs::path& path, const double geo[6]) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  Dataset ds(driver->Create(path.string().c_str(), 3, 2, 1, GDT_Float32, nullptr));
  ASSERT_TRUE(ds);
  ds->SetGeoTransform(const_cast<double*>(geo));
  float v[6] = {1, 2, 3, 4, 5, 6};
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 3, 2, v, 3, 2, GDT_Float32, 0, 0),
            CE_None);
}

TEST_F(RasterIoTest, RotatedRastersAreRefused) {
  const fs::path path = dir_ / "rotated.tif";
  const double geo[6] = {0, 1, 0.1, 10, 0.1, -1};
  WriteWithGeotransform(path, geo);
  try {
    ReadGeoRaster(path);
    FAIL() << "expected sapmvs::InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_NE(std::string(e.what()).find("rotated"), std::string::npos) << e.what();
  }
}

TEST_F(RasterIoTest, SouthUpRastersAreFlippedToNorthUp) {
  const fs::path path = dir_ / "south_up.tif";
  const double geo[6] = {100, 2, 0, 50, 0, 2};  // row 0 is the south edge at y = 50
  WriteWithGeotransform(path, geo);
  const GeoRaster r = ReadGeoRaster(path);
  EXPECT_EQ(r.origin_x, 100);
  EXPECT_EQ(r.origin_y, 54);
  EXPECT_EQ(r.cell_size, 2);
  EXPECT_EQ(r.values, (std::vector<float>{4, 5, 6, 1, 2, 3}));
}

}  // namespace
}  // namespace sapmvs

namespace sapmvs {
namespace {

// report.json names a CRS by EPSG code and name: from an EPSG:n, from a WKT
// that has the code, and from one that has lost it; a custom projection has
// a name but no code.
TEST(IdentifyCrs, EpsgCodeAndNameWhereThereIsOne) {
  const CrsIdentity utm = IdentifyCrs("EPSG:32632");
  EXPECT_EQ(utm.epsg, 32632);
  EXPECT_EQ(utm.name, "WGS 84 / UTM zone 32N");
  EXPECT_EQ(IdentifyCrs(CrsToWkt("EPSG:2056")).epsg, 2056);
  OGRSpatialReference bare;
  bare.SetWellKnownGeogCS("WGS84");
  bare.SetUTM(33, TRUE);
  char* wkt = nullptr;
  ASSERT_EQ(bare.exportToWkt(&wkt), OGRERR_NONE);
  const std::string no_authority = wkt;
  CPLFree(wkt);
  ASSERT_EQ(bare.GetAuthorityCode(nullptr), nullptr) << no_authority;  // only its GEOGCS has one
  EXPECT_EQ(IdentifyCrs(no_authority).epsg, 32633) << no_authority;
  const CrsIdentity custom =
      IdentifyCrs("+proj=tmerc +lat_0=0 +lon_0=7.3 +k=1 +x_0=0 +y_0=0 +ellps=GRS80 +units=m");
  EXPECT_EQ(custom.epsg, 0);
  EXPECT_THROW(IdentifyCrs("not a crs"), Error);
  EXPECT_THROW(IdentifyCrs(""), Error);
}

}  // namespace
}  // namespace sapmvs

#include "block/ecef_to_utm.h"

#include <cpl_error.h>
#include <ogr_spatialref.h>

#include <string>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// ECEF -> geodetic (longitude, latitude, height) -> UTM.
class OgrEcefToUtm : public EcefToUtm {
 public:
  explicit OgrEcefToUtm(int epsg) : epsg_(epsg) {
    CPLErrorHandlerPusher quiet(CPLQuietErrorHandler);
    if (ecef_.importFromEPSG(4978) != OGRERR_NONE ||
        geodetic_.importFromEPSG(4979) != OGRERR_NONE || utm_.importFromEPSG(epsg) != OGRERR_NONE) {
      throw Error("PROJ has no definition of EPSG:4978, EPSG:4979 or EPSG:" + std::to_string(epsg) +
                  " (expected GDAL's proj.db to be installed)");
    }
    for (OGRSpatialReference* s : {&ecef_, &geodetic_, &utm_})
      s->SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // longitude before latitude
    to_geodetic_.reset(OGRCreateCoordinateTransformation(&ecef_, &geodetic_));
    to_utm_.reset(OGRCreateCoordinateTransformation(&geodetic_, &utm_));
    if (!to_geodetic_ || !to_utm_) {
      throw Error("PROJ cannot transform EPSG:4978 to EPSG:" + std::to_string(epsg));
    }
  }

  void Transform(std::vector<double>* x, std::vector<double>* y,
                 std::vector<double>* z) const override {
    const size_t n = x->size();
    if (n == 0) return;
    CPLErrorHandlerPusher quiet(CPLQuietErrorHandler);
    if (!to_geodetic_->Transform(n, x->data(), y->data(), z->data())) {
      throw Error("PROJ failed to transform ECEF points to EPSG:4979");
    }
    const std::vector<double> height = *z;  // the UTM CRS is 2D: heights come from here
    if (!to_utm_->Transform(n, x->data(), y->data(), z->data())) {
      throw Error("PROJ failed to transform points to EPSG:" + std::to_string(epsg_));
    }
    *z = height;
  }

 private:
  int epsg_;
  OGRSpatialReference ecef_, geodetic_, utm_;
  std::unique_ptr<OGRCoordinateTransformation> to_geodetic_, to_utm_;
};

}  // namespace

std::unique_ptr<EcefToUtm> MakeEcefToUtm(int epsg) { return std::make_unique<OgrEcefToUtm>(epsg); }

}  // namespace sapmvs

#pragma once
// Earth-centred coordinates to UTM, through PROJ as GDAL's OGR offers it. GDAL
// code: it lives in the GDAL module (cli/gdal_module.h), which the binary
// loads only when a step needs it.

#include <memory>
#include <vector>

namespace sapmvs {

class EcefToUtm {
 public:
  virtual ~EcefToUtm() = default;
  // In place: x, y, z in ECEF (EPSG:4978) to easting, northing and
  // ellipsoidal height in the UTM zone. Throws sapmvs::Error naming the CRS
  // when PROJ fails.
  virtual void Transform(std::vector<double>* x, std::vector<double>* y,
                         std::vector<double>* z) const = 0;
};

// UTM zone `epsg` (326xx or 327xx); throws when PROJ has no definition.
std::unique_ptr<EcefToUtm> MakeEcefToUtm(int epsg);

}  // namespace sapmvs

#pragma once
// A block in a local topocentric frame (OpenSfM's: east, north, up about a
// geodetic reference point) moved into the UTM zone of that point, so that
// every output carries an EPSG code; and ODM's variant of it, UTM less the
// reference point (MoveUtmOffsetToUtm), told apart by FitFramesToGps.
//
// Points, camera centres included, go exactly: ENU -> ECEF (WGS84, by
// formula) -> geodetic -> UTM through GDAL's OGR (PROJ). A camera's rotation
// cannot go exactly: UTM is no rigid copy of ENU. Its grid north turns from
// true north by the meridian convergence, its horizontal scale is the
// projection's k (0.9996 on the central meridian, up to ~1.001 at the zone's
// edge) while heights keep scale 1, and ENU's up tilts away from the local
// vertical by (distance from the origin) / (Earth radius). Cameras are turned
// by one rotation, that of the map at the block's centre (the closest
// rotation to its Jacobian there: mostly the convergence). What that leaves
// is measured on the block's own points: the largest change of a point's
// reprojection, in pixels (TopocentricToUtmReport).

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "block/ecef_to_utm.h"
#include "sapmvs/block/block.h"

namespace sapmvs {

// A geodetic point: WGS84 latitude and longitude in degrees, altitude in
// metres (the height system of whatever gave it; kept as it is).
struct GeoReference {
  double latitude = 0;
  double longitude = 0;
  double altitude = 0;

  // Empty when usable: finite, latitude in [-80, 84] (the UTM zones) and
  // longitude in [-180, 180]; else what was expected, naming the value.
  std::string Problem() const;
};

// The geodetic coordinates (WGS84) of an ECEF point.
GeoReference GeodeticOf(const Eigen::Vector3d& ecef);

// The UTM zone of a point from its longitude alone (no Norway or Svalbard
// exceptions): EPSG 326zz north of the equator, 327zz south.
int UtmEpsgFor(const GeoReference& point);

class TopocentricToUtm {
 public:
  // Throws sapmvs::Error when `reference` has a Problem() or PROJ cannot
  // make the transformation.
  explicit TopocentricToUtm(const GeoReference& reference);
  ~TopocentricToUtm();
  TopocentricToUtm(const TopocentricToUtm&) = delete;
  TopocentricToUtm& operator=(const TopocentricToUtm&) = delete;

  int epsg() const { return epsg_; }
  // The reference point in ECEF, and the ENU axes there as columns in ECEF:
  // X_ecef = origin_ecef() + enu_to_ecef() * X_enu, exactly.
  const Eigen::Vector3d& origin_ecef() const { return origin_ecef_; }
  const Eigen::Matrix3d& enu_to_ecef() const { return enu_to_ecef_; }

  // Exact, in place: ENU metres to UTM easting, northing and height.
  void Transform(std::vector<Eigen::Vector3d>* points) const;
  Eigen::Vector3d Transform(const Eigen::Vector3d& enu) const;

  // The rotation closest to the map's Jacobian at `enu` (UTM directions =
  // R * ENU directions there), and the map's horizontal scale there.
  Eigen::Matrix3d LocalRotation(const Eigen::Vector3d& enu, double* scale = nullptr) const;

 private:
  GeoReference reference_;
  int epsg_ = 0;
  Eigen::Vector3d origin_ecef_;
  Eigen::Matrix3d enu_to_ecef_;
  std::unique_ptr<EcefToUtm> ecef_to_utm_;
};

struct TopocentricToUtmReport {
  int epsg = 0;
  double convergence_deg = 0;  // grid north from ENU north at the block's centre
  double scale = 1;            // horizontal scale of the map there
  // Largest change of a sparse point's projection into an image that sees it,
  // ENU camera versus moved camera (pixels); -1 when the block has no points.
  double max_reprojection_change_px = -1;
  int points_checked = 0;
};

// Moves `block`'s cameras and sparse points from the topocentric frame about
// `reference` into its UTM zone and sets block->crs to "EPSG:n".
TopocentricToUtmReport MoveTopocentricToUtm(const GeoReference& reference, Block* block);

// OpenDroneMap (2.x) leaves as opensfm/reconstruction.json not OpenSfM's
// topocentric reconstruction (kept as reconstruction.topocentric.json) but
// its `export_geocoords` output: UTM easting and northing less those of the
// reference point, heights as they are, reference_lla unchanged. Its move to
// UTM is a translation, exact.
TopocentricToUtmReport MoveUtmOffsetToUtm(const GeoReference& reference, Block* block);

// Which of the two frames a reconstruction's camera centres are in, told by
// the GPS positions OpenSfM stores with each shot (`gps_position`, always
// topocentric): the horizontal RMS distance of the centres from them in each
// reading. The two differ by the grid convergence times the distance from the
// reference point (2 m at 140 m on the ODM block), well above what
// alignment to the GPS leaves.
struct FrameFit {
  double topocentric_rms = 0;
  double utm_offset_rms = 0;
};
FrameFit FitFramesToGps(const TopocentricToUtm& map, const std::vector<Eigen::Vector3d>& centres,
                        const std::vector<Eigen::Vector3d>& gps_enu);

}  // namespace sapmvs

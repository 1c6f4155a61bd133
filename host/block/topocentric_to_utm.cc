#include "block/topocentric_to_utm.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "block/ecef_to_utm.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// WGS84, the ellipsoid of EPSG:4978/4979 and of OpenSfM's own conversion.
constexpr double kSemiMajor = 6378137.0;
constexpr double kFlattening = 1.0 / 298.257223563;
constexpr double kE2 = kFlattening * (2 - kFlattening);
// Sparse points checked for the reprojection change: enough to find the
// worst corner of a block, few enough to cost nothing beside the matching.
constexpr size_t kMaxCheckedPoints = 2000;

double Radians(double deg) { return deg * M_PI / 180.0; }

}  // namespace

std::string GeoReference::Problem() const {
  std::ostringstream s;
  s.precision(10);
  if (!std::isfinite(latitude) || !std::isfinite(longitude) || !std::isfinite(altitude)) {
    s << "finite numbers (latitude " << latitude << ", longitude " << longitude << ", altitude "
      << altitude << ")";
  } else if (latitude < -90 || latitude > 90) {
    s << "a latitude in [-90, 90] degrees (latitude = " << latitude << ")";
  } else if (latitude < -80 || latitude > 84) {
    s << "a latitude inside the UTM zones, [-80, 84] degrees (latitude = " << latitude << ")";
  } else if (longitude < -180 || longitude > 180) {
    s << "a longitude in [-180, 180] degrees (longitude = " << longitude << ")";
  }
  return s.str();
}

GeoReference GeodeticOf(const Eigen::Vector3d& ecef) {
  GeoReference g;
  const double p = std::hypot(ecef.x(), ecef.y());
  double lat = std::atan2(ecef.z(), p * (1 - kE2));
  double h = 0;
  // Bowring's iteration; five rounds reach a millimetre at any height a
  // camera flies.
  for (int i = 0; i < 5; ++i) {
    const double n = kSemiMajor / std::sqrt(1 - kE2 * std::sin(lat) * std::sin(lat));
    h = p / std::cos(lat) - n;
    lat = std::atan2(ecef.z(), p * (1 - kE2 * n / (n + h)));
  }
  g.latitude = lat * 180 / M_PI;
  g.longitude = std::atan2(ecef.y(), ecef.x()) * 180 / M_PI;
  g.altitude = h;
  return g;
}

int UtmEpsgFor(const GeoReference& point) {
  const int zone = std::clamp(static_cast<int>(std::floor((point.longitude + 180) / 6)) + 1, 1, 60);
  return (point.latitude >= 0 ? 32600 : 32700) + zone;
}

TopocentricToUtm::TopocentricToUtm(const GeoReference& reference) : reference_(reference) {
  if (const std::string p = reference.Problem(); !p.empty()) {
    throw Error("reference point: expected " + p);
  }
  epsg_ = UtmEpsgFor(reference);
  const double lat = Radians(reference.latitude), lon = Radians(reference.longitude);
  const double h = reference.altitude;
  const double n = kSemiMajor / std::sqrt(1 - kE2 * std::sin(lat) * std::sin(lat));
  origin_ecef_ =
      Eigen::Vector3d((n + h) * std::cos(lat) * std::cos(lon),
                      (n + h) * std::cos(lat) * std::sin(lon), (n * (1 - kE2) + h) * std::sin(lat));
  // Columns: east, north and up at the reference point, in ECEF.
  enu_to_ecef_.col(0) << -std::sin(lon), std::cos(lon), 0;
  enu_to_ecef_.col(1) << -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon),
      std::cos(lat);
  enu_to_ecef_.col(2) << std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon),
      std::sin(lat);
  ecef_to_utm_ = MakeEcefToUtm(epsg_);
}

TopocentricToUtm::~TopocentricToUtm() = default;

void TopocentricToUtm::Transform(std::vector<Eigen::Vector3d>* points) const {
  const size_t n = points->size();
  if (n == 0) return;
  std::vector<double> x(n), y(n), z(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d e = origin_ecef_ + enu_to_ecef_ * (*points)[i];
    x[i] = e.x();
    y[i] = e.y();
    z[i] = e.z();
  }
  ecef_to_utm_->Transform(&x, &y, &z);
  for (size_t i = 0; i < n; ++i) (*points)[i] = Eigen::Vector3d(x[i], y[i], z[i]);
}

Eigen::Vector3d TopocentricToUtm::Transform(const Eigen::Vector3d& enu) const {
  std::vector<Eigen::Vector3d> p = {enu};
  Transform(&p);
  return p[0];
}

Eigen::Matrix3d TopocentricToUtm::LocalRotation(const Eigen::Vector3d& enu, double* scale) const {
  // Central differences over 1 m: the map's second derivatives are ~1/R, so
  // the truncation error (~1e-13) is far below the rounding of UTM
  // coordinates (~1e-9 m over 2 m, 5e-10).
  constexpr double kStep = 1.0;
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 3; ++i) {
    p.push_back(enu + kStep * Eigen::Vector3d::Unit(i));
    p.push_back(enu - kStep * Eigen::Vector3d::Unit(i));
  }
  Transform(&p);
  Eigen::Matrix3d j;
  for (int i = 0; i < 3; ++i) j.col(i) = (p[2 * i] - p[2 * i + 1]) / (2 * kStep);
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(j, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) throw Error("ENU to UTM map is a reflection (internal error)");
  if (scale) *scale = 0.5 * (j.col(0).head<2>().norm() + j.col(1).head<2>().norm());
  return r;
}

TopocentricToUtmReport MoveTopocentricToUtm(const GeoReference& reference, Block* block) {
  const TopocentricToUtm map(reference);
  TopocentricToUtmReport report;
  report.epsg = map.epsg();

  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const BlockImage& im : block->images) centre += im.camera.center();
  if (!block->images.empty()) centre /= static_cast<double>(block->images.size());
  const Eigen::Matrix3d r = map.LocalRotation(centre, &report.scale);
  // Grid north (UTM +Y) seen from ENU: its east component is the convergence.
  const Eigen::Vector3d grid_north = r.transpose() * Eigen::Vector3d::UnitY();
  report.convergence_deg = std::atan2(grid_north.x(), grid_north.y()) * 180 / M_PI;

  const std::vector<BlockImage> enu_images = block->images;
  std::vector<Eigen::Vector3d> centres;
  for (const BlockImage& im : block->images) centres.push_back(im.camera.center());
  map.Transform(&centres);
  for (size_t i = 0; i < block->images.size(); ++i) {
    Camera& cam = block->images[i].camera;
    // x_cam = R_wc (X_enu - C) = R_wc r^T (X_utm - C_utm), to first order.
    cam = Camera(cam.intrinsics(), cam.rotation() * r.transpose(), centres[i]);
  }

  const size_t stride = std::max<size_t>(1, block->sparse_points.size() / kMaxCheckedPoints);
  std::vector<Eigen::Vector3d> checked_enu;
  for (size_t i = 0; i < block->sparse_points.size(); i += stride)
    checked_enu.push_back(block->sparse_points[i]);
  map.Transform(&block->sparse_points);
  std::vector<Eigen::Vector3d> checked_utm = checked_enu;
  map.Transform(&checked_utm);
  double worst = -1;
  for (size_t p = 0; p < checked_enu.size(); ++p) {
    for (size_t i = 0; i < enu_images.size(); ++i) {
      const Camera& a = enu_images[i].camera;
      if (a.Depth(checked_enu[p]) <= 0) continue;
      const Eigen::Vector2d uv = a.Project(checked_enu[p]);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() > a.width() - 1 || uv.y() > a.height() - 1) continue;
      const Eigen::Vector2d moved = block->images[i].camera.Project(checked_utm[p]);
      worst = std::max(worst, (moved - uv).norm());
    }
  }
  report.points_checked = static_cast<int>(checked_enu.size());
  report.max_reprojection_change_px = worst;
  block->crs = "EPSG:" + std::to_string(map.epsg());
  return report;
}

TopocentricToUtmReport MoveUtmOffsetToUtm(const GeoReference& reference, Block* block) {
  const TopocentricToUtm map(reference);
  const Eigen::Vector3d origin = map.Transform(Eigen::Vector3d::Zero());
  const Eigen::Vector3d shift(origin.x(), origin.y(), 0);
  for (BlockImage& im : block->images) {
    const Camera& c = im.camera;
    im.camera = Camera(c.intrinsics(), c.rotation(), c.center() + shift);
  }
  for (Eigen::Vector3d& p : block->sparse_points) p += shift;
  TopocentricToUtmReport report;
  report.epsg = map.epsg();
  report.max_reprojection_change_px = block->sparse_points.empty() ? -1 : 0;
  report.points_checked = static_cast<int>(block->sparse_points.size());
  block->crs = "EPSG:" + std::to_string(map.epsg());
  return report;
}

FrameFit FitFramesToGps(const TopocentricToUtm& map, const std::vector<Eigen::Vector3d>& centres,
                        const std::vector<Eigen::Vector3d>& gps_enu) {
  FrameFit fit;
  if (centres.empty() || centres.size() != gps_enu.size()) return fit;
  std::vector<Eigen::Vector3d> grid = gps_enu;
  grid.push_back(Eigen::Vector3d::Zero());
  map.Transform(&grid);
  const Eigen::Vector3d origin = grid.back();
  double topo = 0, offset = 0;
  for (size_t i = 0; i < centres.size(); ++i) {
    topo += (centres[i] - gps_enu[i]).head<2>().squaredNorm();
    offset += (centres[i] - (grid[i] - origin)).head<2>().squaredNorm();
  }
  fit.topocentric_rms = std::sqrt(topo / static_cast<double>(centres.size()));
  fit.utm_offset_rms = std::sqrt(offset / static_cast<double>(centres.size()));
  return fit;
}

}  // namespace sapmvs

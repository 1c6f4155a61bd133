#include "sapmvs/block/camera.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs {
namespace {

void RequirePositive(double v, const char* name, const std::string& what) {
  if (!std::isfinite(v) || v <= 0) {
    throw Error(what + ": " + name + " = " + std::to_string(v) + ", expected a positive number");
  }
}

}  // namespace

Eigen::Vector2d Distortion::Apply(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

Intrinsics Intrinsics::FromFocalAndPixel(double focal_mm, double pixel_um, int width, int height,
                                         const Eigen::Vector2d& pp_offset_mm) {
  RequirePositive(focal_mm, "focal length (mm)", "camera");
  RequirePositive(pixel_um, "pixel size (um)", "camera");
  const double pixel_mm = pixel_um * 1e-3;
  return FromFocalAndSensor(focal_mm, pixel_mm * width, pixel_mm * height, width, height,
                            pp_offset_mm);
}

Intrinsics Intrinsics::FromFocalAndSensor(double focal_mm, double sensor_width_mm,
                                          double sensor_height_mm, int width, int height,
                                          const Eigen::Vector2d& pp_offset_mm) {
  RequirePositive(focal_mm, "focal length (mm)", "camera");
  RequirePositive(sensor_width_mm, "sensor width (mm)", "camera");
  RequirePositive(sensor_height_mm, "sensor height (mm)", "camera");
  RequirePositive(width, "width (px)", "camera");
  RequirePositive(height, "height (px)", "camera");
  const double px = sensor_width_mm / width;    // mm per pixel, x
  const double py = sensor_height_mm / height;  // mm per pixel, y
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = focal_mm / px;
  k.fy = focal_mm / py;
  // The photogrammetric image frame has y up; pixel rows grow downwards.
  k.cx = 0.5 * (width - 1) + pp_offset_mm.x() / px;
  k.cy = 0.5 * (height - 1) - pp_offset_mm.y() / py;
  return k;
}

Intrinsics Intrinsics::FromPixels(double fx, double fy, double cx, double cy, int width,
                                  int height) {
  Intrinsics k;
  k.width = width;
  k.height = height;
  k.fx = fx;
  k.fy = fy;
  k.cx = cx;
  k.cy = cy;
  return k;
}

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

Intrinsics Intrinsics::Scaled(double scale) const {
  Intrinsics k = *this;
  k.width = static_cast<int>(std::lround(width * scale));
  k.height = static_cast<int>(std::lround(height * scale));
  k.fx = fx * scale;
  k.fy = fy * scale;
  // Pixel centres sit at half-integers of the continuous image frame.
  k.cx = (cx + 0.5) * scale - 0.5;
  k.cy = (cy + 0.5) * scale - 0.5;
  return k;
}

void Intrinsics::Validate(const std::string& what) const {
  RequirePositive(width, "width (px)", what);
  RequirePositive(height, "height (px)", what);
  RequirePositive(fx, "fx (px)", what);
  RequirePositive(fy, "fy (px)", what);
  for (double v :
       {cx, cy, distortion.k1, distortion.k2, distortion.k3, distortion.p1, distortion.p2}) {
    if (!std::isfinite(v)) throw Error(what + ": non-finite principal point or distortion");
  }
}

Camera::Camera(const Intrinsics& intrinsics, const Eigen::Matrix3d& r_wc,
               const Eigen::Vector3d& center)
    : intrinsics_(intrinsics), r_wc_(r_wc), center_(center) {}

Camera Camera::FromAngles(const Intrinsics& intrinsics, const Eigen::Vector3d& center, double a1,
                          double a2, double a3, AngleOrder order, AngleUnit unit) {
  return Camera(intrinsics, WorldToCameraFromAngles(a1, a2, a3, order, unit), center);
}

Camera Camera::FromCameraToWorld(const Intrinsics& intrinsics, const Eigen::Vector3d& center,
                                 const Eigen::Matrix3d& r_pg) {
  return Camera(intrinsics, (r_pg * PhotoToOpenCv()).transpose(), center);
}

Camera Camera::FromProjectionMatrix(const Eigen::Matrix<double, 3, 4>& p, int width, int height,
                                    const std::string& what) {
  if (!p.allFinite()) throw Error(what + ": non-finite entry");
  const Eigen::Matrix3d m = p.leftCols<3>();
  if (std::abs(m.determinant()) < 1e-12 * std::pow(m.norm(), 3)) {
    throw Error(what + ": left 3x3 block is singular, not a camera");
  }
  // RQ decomposition of M via QR of the row-reversed transpose.
  Eigen::Matrix3d flip;
  flip << 0, 0, 1, 0, 1, 0, 1, 0, 0;
  Eigen::HouseholderQR<Eigen::Matrix3d> qr((flip * m).transpose());
  Eigen::Matrix3d q = qr.householderQ();
  Eigen::Matrix3d r = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d k = flip * r.transpose() * flip;
  Eigen::Matrix3d rot = flip * q.transpose();
  // Make the diagonal of K positive; the sign goes into R.
  const Eigen::Matrix3d d = k.diagonal().cwiseSign().asDiagonal();
  k = k * d;
  rot = d * rot;
  // P is defined up to scale (also a negative one): keep R proper.
  Eigen::Vector3d t = (k.inverse() * p.col(3));
  if (rot.determinant() < 0) {
    rot = -rot;
    t = -t;
  }
  k /= k(2, 2);
  if (std::abs(k(0, 1)) > 1e-3 * k(0, 0)) {
    throw Error(what + ": skew " + std::to_string(k(0, 1)) +
                " is not supported (expected a camera with square-grid pixels)");
  }
  Intrinsics in = Intrinsics::FromPixels(k(0, 0), k(1, 1), k(0, 2), k(1, 2), width, height);
  const Eigen::Vector3d center = -rot.transpose() * t;
  return Camera(in, rot, center);
}

Eigen::Matrix<double, 3, 4> Camera::ProjectionMatrix() const {
  Eigen::Matrix<double, 3, 4> rt;
  rt.leftCols<3>() = r_wc_;
  rt.col(3) = -r_wc_ * center_;
  return intrinsics_.K() * rt;
}

Eigen::Vector2d Camera::Project(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d c = ToCamera(x);
  if (!(c.z() > 0)) return {kNaN, kNaN};
  return {intrinsics_.fx * c.x() / c.z() + intrinsics_.cx,
          intrinsics_.fy * c.y() / c.z() + intrinsics_.cy};
}

Eigen::Vector2d Camera::ProjectDistorted(const Eigen::Vector3d& x) const {
  const Eigen::Vector3d c = ToCamera(x);
  if (!(c.z() > 0)) return {kNaN, kNaN};
  const Eigen::Vector2d d = intrinsics_.distortion.Apply({c.x() / c.z(), c.y() / c.z()});
  return {intrinsics_.fx * d.x() + intrinsics_.cx, intrinsics_.fy * d.y() + intrinsics_.cy};
}

Eigen::Vector3d Camera::Ray(const Eigen::Vector2d& uv) const {
  const Eigen::Vector3d c((uv.x() - intrinsics_.cx) / intrinsics_.fx,
                          (uv.y() - intrinsics_.cy) / intrinsics_.fy, 1.0);
  return (r_wc_.transpose() * c).normalized();
}

Eigen::Vector3d Camera::BackProject(const Eigen::Vector2d& uv, double depth) const {
  const Eigen::Vector3d c((uv.x() - intrinsics_.cx) / intrinsics_.fx * depth,
                          (uv.y() - intrinsics_.cy) / intrinsics_.fy * depth, depth);
  return r_wc_.transpose() * c + center_;
}

bool Camera::InImage(const Eigen::Vector2d& uv, double margin) const {
  return uv.x() >= -0.5 + margin && uv.y() >= -0.5 + margin && uv.x() <= width() - 0.5 - margin &&
         uv.y() <= height() - 0.5 - margin;
}

double Camera::Footprint(const Eigen::Vector3d& x, const Eigen::Vector3d& normal) const {
  const Eigen::Vector3d v = x - center_;
  const double range = v.norm();
  const double depth = Depth(x);
  if (!(depth > 0) || range == 0) return kNaN;
  const double cos_theta = depth / range;
  const double cos_alpha = std::abs(v.dot(normal.normalized())) / range;
  if (cos_alpha < 1e-9) return kNaN;
  return std::sqrt(depth * depth * cos_theta / (intrinsics_.fx * intrinsics_.fy * cos_alpha));
}

double Camera::FootprintFacing(const Eigen::Vector3d& x) const {
  return Footprint(x, (x - center_).normalized());
}

Camera Camera::WithIntrinsics(const Intrinsics& intrinsics) const {
  return Camera(intrinsics, r_wc_, center_);
}

Camera Camera::Pinhole() const {
  Intrinsics k = intrinsics_;
  k.distortion = Distortion{};
  return WithIntrinsics(k);
}

Camera Camera::Translated(const Eigen::Vector3d& origin) const {
  return Camera(intrinsics_, r_wc_, center_ - origin);
}

}  // namespace sapmvs

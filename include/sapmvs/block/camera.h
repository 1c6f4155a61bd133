#pragma once
// The camera model: an OpenCV pinhole camera with optional Brown distortion,
// in double precision. Conventions (see rotation.h for the angle ones):
//   x_cam = R_wc (X - C), camera frame x right, y down, z forward;
//   u = fx x/z + cx, v = fy y/z + cy, pixel (0, 0) = centre of the top-left
//   pixel. Distortion (k1 k2 k3 p1 p2) is OpenCV's, applied to x/z, y/z.
// Images with distortion are undistorted once at load (image_io.h), keeping
// fx fy cx cy, so everything after loading sees a pinhole camera.

#include <Eigen/Core>
#include <string>

#include "sapmvs/block/rotation.h"

namespace sapmvs {

struct Distortion {
  double k1 = 0, k2 = 0, k3 = 0;  // Radial, on normalised coordinates.
  double p1 = 0, p2 = 0;          // Tangential (OpenCV's order p1, p2).
  bool IsZero() const { return k1 == 0 && k2 == 0 && k3 == 0 && p1 == 0 && p2 == 0; }
  // Applies the model to normalised coordinates (x/z, y/z).
  Eigen::Vector2d Apply(const Eigen::Vector2d& xn) const;
};

struct Intrinsics {
  int width = 0;          // pixels
  int height = 0;         // pixels
  double fx = 0, fy = 0;  // focal length in pixels
  double cx = 0, cy = 0;  // principal point in pixels, (0, 0) = centre of the top-left pixel
  Distortion distortion;

  // Focal length in mm and pixel pitch in micrometres. `pp_offset_mm` is the
  // principal point's offset from the image centre in the photogrammetric
  // image frame (x right, y up), in mm.
  static Intrinsics FromFocalAndPixel(
      double focal_mm, double pixel_um, int width, int height,
      const Eigen::Vector2d& pp_offset_mm = Eigen::Vector2d::Zero());
  // Focal length and sensor size in mm (the sensor spans all pixels); pixels
  // may be non-square.
  static Intrinsics FromFocalAndSensor(
      double focal_mm, double sensor_width_mm, double sensor_height_mm, int width, int height,
      const Eigen::Vector2d& pp_offset_mm = Eigen::Vector2d::Zero());
  static Intrinsics FromPixels(double fx, double fy, double cx, double cy, int width, int height);

  Eigen::Matrix3d K() const;
  double MeanFocal() const { return 0.5 * (fx + fy); }
  // The same camera on an image resampled by `scale` (0.5 = pyramid level 1).
  Intrinsics Scaled(double scale) const;
  // Throws sapmvs::Error naming `what` when a value is non-finite or out of range.
  void Validate(const std::string& what) const;
};

class Camera {
 public:
  Camera() = default;
  // `r_wc` is the OpenCV world-to-camera rotation, `center` the projection
  // centre in world coordinates.
  Camera(const Intrinsics& intrinsics, const Eigen::Matrix3d& r_wc, const Eigen::Vector3d& center);

  // Projection centre + three angles (rotation.h).
  static Camera FromAngles(const Intrinsics& intrinsics, const Eigen::Vector3d& center, double a1,
                           double a2, double a3, AngleOrder order, AngleUnit unit);
  // Projection centre + R_pg (photogrammetric camera-to-world).
  static Camera FromCameraToWorld(const Intrinsics& intrinsics, const Eigen::Vector3d& center,
                                  const Eigen::Matrix3d& r_pg);
  // A 3x4 projection matrix P ~ K [R | t], decomposed (RQ) into K, R and C.
  // The image size is not part of P and is given separately. Skew, if any,
  // is dropped; throws when it exceeds 1e-3 of the focal length.
  static Camera FromProjectionMatrix(const Eigen::Matrix<double, 3, 4>& p, int width, int height,
                                     const std::string& what = "projection matrix");

  const Intrinsics& intrinsics() const { return intrinsics_; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }
  const Eigen::Matrix3d& rotation() const { return r_wc_; }  // R_wc
  const Eigen::Vector3d& center() const { return center_; }
  Eigen::Matrix<double, 3, 4> ProjectionMatrix() const;  // K [R | -R C], undistorted pixels

  Eigen::Vector3d ToCamera(const Eigen::Vector3d& x) const { return r_wc_ * (x - center_); }
  // Depth along the optical axis (camera z); negative behind the camera.
  double Depth(const Eigen::Vector3d& x) const { return ToCamera(x).z(); }
  // Pinhole projection into the undistorted image. NaN when `x` is not in front.
  Eigen::Vector2d Project(const Eigen::Vector3d& x) const;
  // Projection into the original (distorted) image.
  Eigen::Vector2d ProjectDistorted(const Eigen::Vector3d& x) const;
  // Unit world-frame direction of the ray through undistorted pixel `uv`.
  Eigen::Vector3d Ray(const Eigen::Vector2d& uv) const;
  // World point on the ray through `uv` at optical-axis depth `depth`.
  Eigen::Vector3d BackProject(const Eigen::Vector2d& uv, double depth) const;
  // Optical axis (camera +z) in world coordinates.
  Eigen::Vector3d ViewingDirection() const { return r_wc_.row(2).transpose(); }
  bool InImage(const Eigen::Vector2d& uv, double margin = 0) const;

  // Side of the square that one pixel covers on the plane through `x` with
  // unit normal `normal` (the ground sample distance there): sqrt of
  // depth^2 cos(theta) / (fx fy cos(alpha)), theta the ray's angle to the
  // optical axis and alpha its incidence on the plane.
  double Footprint(const Eigen::Vector3d& x, const Eigen::Vector3d& normal) const;
  // Footprint on a plane facing the camera (normal = -ray): depth/f for a
  // point on the optical axis.
  double FootprintFacing(const Eigen::Vector3d& x) const;

  Camera WithIntrinsics(const Intrinsics& intrinsics) const;
  // The same camera, its distortion dropped (after undistorting the image).
  Camera Pinhole() const;
  // On an image resampled by `scale`.
  Camera Scaled(double scale) const { return WithIntrinsics(intrinsics_.Scaled(scale)); }
  // The same camera in a frame whose origin is `origin` (local coordinates).
  Camera Translated(const Eigen::Vector3d& origin) const;

 private:
  Intrinsics intrinsics_;
  Eigen::Matrix3d r_wc_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center_ = Eigen::Vector3d::Zero();
};

}  // namespace sapmvs

#pragma once
// Rotation conventions, written down once.
//
// Photogrammetric camera frame: x right, y up, z backwards (the camera looks
// along -z). OpenCV camera frame: x right, y down, z forward. They differ by
// kPhotoToOpenCv = diag(1, -1, -1).
//
// Angles (omega, phi, kappa) define R_pg, the rotation that takes vectors from
// the photogrammetric camera frame to the world frame:
//   omega-phi-kappa (European / PATB):  R_pg = Rx(omega) * Ry(phi) * Rz(kappa)
//   phi-omega-kappa (common in Chinese software, the paper's Tables 2 and 5):
//                                       R_pg = Ry(phi) * Rx(omega) * Rz(kappa)
// with right-handed elementary rotations, e.g. Rz(k) = [c -s 0; s c 0; 0 0 1].
// So a level camera (omega = phi = 0) with kappa = 0 has its image x axis
// (columns) along world +X and its image top towards +Y; kappa = 90 deg turns
// image x to +Y. For a frame camera flown with image x along track, kappa is
// the heading: flying +X gives kappa = 0, -X kappa = 180 deg (200 gon).
//
// Everything downstream uses R_wc, the OpenCV world-to-camera rotation:
//   x_cam = R_wc (X - C),   R_wc = (R_pg * kPhotoToOpenCv)^T.

#include <Eigen/Core>
#include <string>
#include <string_view>

namespace sapmvs {

enum class AngleOrder { kOmegaPhiKappa, kPhiOmegaKappa };
enum class AngleUnit { kDegree, kGon, kRadian };

// Parses "omega-phi-kappa"/"opk" and "phi-omega-kappa"/"pok"; throws
// sapmvs::Error naming the value and the accepted spellings otherwise.
AngleOrder ParseAngleOrder(std::string_view text);
// Parses "deg"/"degree(s)", "gon"/"grad", "rad"/"radian(s)".
AngleUnit ParseAngleUnit(std::string_view text);
std::string ToString(AngleOrder order);
std::string ToString(AngleUnit unit);

double ToRadians(double angle, AngleUnit unit);
double FromRadians(double radians, AngleUnit unit);

Eigen::Matrix3d RotX(double radians);
Eigen::Matrix3d RotY(double radians);
Eigen::Matrix3d RotZ(double radians);

// diag(1, -1, -1): photogrammetric camera frame <-> OpenCV camera frame.
Eigen::Matrix3d PhotoToOpenCv();

// R_pg (photogrammetric camera -> world) from three angles given in `order`:
// a1, a2, a3 are (omega, phi, kappa) or (phi, omega, kappa) as written.
Eigen::Matrix3d CameraToWorldFromAngles(double a1, double a2, double a3, AngleOrder order,
                                        AngleUnit unit);

// R_wc (OpenCV world -> camera) from three angles, as above.
Eigen::Matrix3d WorldToCameraFromAngles(double a1, double a2, double a3, AngleOrder order,
                                        AngleUnit unit);

// Recovers the angles (in `order` and `unit`) from an OpenCV R_wc. The middle
// angle lies in [-90, 90] degrees; near gimbal lock the first angle is 0.
Eigen::Vector3d AnglesFromWorldToCamera(const Eigen::Matrix3d& r_wc, AngleOrder order,
                                        AngleUnit unit);

// Closest rotation (SVD) to `m`; throws when `m` is far from orthonormal
// (max |M^T M - I| > tolerance) or a reflection, naming `what`.
Eigen::Matrix3d CheckedRotation(const Eigen::Matrix3d& m, const std::string& what,
                                double tolerance = 1e-4);

}  // namespace sapmvs

#include "sapmvs/block/rotation.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

constexpr double kPi = 3.14159265358979323846;

}  // namespace

AngleOrder ParseAngleOrder(std::string_view text) {
  const std::string t = Lower(text);
  if (t == "omega-phi-kappa" || t == "opk") return AngleOrder::kOmegaPhiKappa;
  if (t == "phi-omega-kappa" || t == "pok") return AngleOrder::kPhiOmegaKappa;
  throw Error("unknown angle order '" + std::string(text) +
              "': expected omega-phi-kappa (opk) or phi-omega-kappa (pok)");
}

AngleUnit ParseAngleUnit(std::string_view text) {
  const std::string t = Lower(text);
  if (t == "deg" || t == "degree" || t == "degrees") return AngleUnit::kDegree;
  if (t == "gon" || t == "grad" || t == "gons") return AngleUnit::kGon;
  if (t == "rad" || t == "radian" || t == "radians") return AngleUnit::kRadian;
  throw Error("unknown angle unit '" + std::string(text) + "': expected deg, gon or rad");
}

std::string ToString(AngleOrder order) {
  return order == AngleOrder::kOmegaPhiKappa ? "omega-phi-kappa" : "phi-omega-kappa";
}

std::string ToString(AngleUnit unit) {
  switch (unit) {
    case AngleUnit::kDegree:
      return "deg";
    case AngleUnit::kGon:
      return "gon";
    case AngleUnit::kRadian:
      return "rad";
  }
  return "?";
}

double ToRadians(double angle, AngleUnit unit) {
  switch (unit) {
    case AngleUnit::kDegree:
      return angle * kPi / 180.0;
    case AngleUnit::kGon:
      return angle * kPi / 200.0;
    case AngleUnit::kRadian:
      return angle;
  }
  return angle;
}

double FromRadians(double radians, AngleUnit unit) {
  switch (unit) {
    case AngleUnit::kDegree:
      return radians * 180.0 / kPi;
    case AngleUnit::kGon:
      return radians * 200.0 / kPi;
    case AngleUnit::kRadian:
      return radians;
  }
  return radians;
}

Eigen::Matrix3d RotX(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, c, -s, 0, s, c;
  return r;
}

Eigen::Matrix3d RotY(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d r;
  r << c, 0, s, 0, 1, 0, -s, 0, c;
  return r;
}

Eigen::Matrix3d RotZ(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix3d r;
  r << c, -s, 0, s, c, 0, 0, 0, 1;
  return r;
}

Eigen::Matrix3d PhotoToOpenCv() { return Eigen::Vector3d(1, -1, -1).asDiagonal(); }

Eigen::Matrix3d CameraToWorldFromAngles(double a1, double a2, double a3, AngleOrder order,
                                        AngleUnit unit) {
  const double r1 = ToRadians(a1, unit), r2 = ToRadians(a2, unit), r3 = ToRadians(a3, unit);
  if (order == AngleOrder::kOmegaPhiKappa) return RotX(r1) * RotY(r2) * RotZ(r3);
  return RotY(r1) * RotX(r2) * RotZ(r3);
}

Eigen::Matrix3d WorldToCameraFromAngles(double a1, double a2, double a3, AngleOrder order,
                                        AngleUnit unit) {
  return (CameraToWorldFromAngles(a1, a2, a3, order, unit) * PhotoToOpenCv()).transpose();
}

Eigen::Vector3d AnglesFromWorldToCamera(const Eigen::Matrix3d& r_wc, AngleOrder order,
                                        AngleUnit unit) {
  const Eigen::Matrix3d r = (r_wc.transpose() * PhotoToOpenCv());  // R_pg
  double omega, phi, kappa;
  if (order == AngleOrder::kOmegaPhiKappa) {
    // R = Rx(w)Ry(p)Rz(k): r13 = sin p, r23 = -cos p sin w, r33 = cos p cos w,
    // r12 = -cos p sin k, r11 = cos p cos k.
    phi = std::asin(std::clamp(r(0, 2), -1.0, 1.0));
    omega = std::atan2(-r(1, 2), r(2, 2));
    kappa = std::atan2(-r(0, 1), r(0, 0));
    Eigen::Vector3d out(FromRadians(omega, unit), FromRadians(phi, unit), FromRadians(kappa, unit));
    return out;
  }
  // R = Ry(p)Rx(w)Rz(k): r23 = -sin w, r13 = sin p cos w, r33 = cos p cos w,
  // r21 = cos w sin k, r22 = cos w cos k.
  omega = std::asin(std::clamp(-r(1, 2), -1.0, 1.0));
  phi = std::atan2(r(0, 2), r(2, 2));
  kappa = std::atan2(r(1, 0), r(1, 1));
  return Eigen::Vector3d(FromRadians(phi, unit), FromRadians(omega, unit),
                         FromRadians(kappa, unit));
}

Eigen::Matrix3d CheckedRotation(const Eigen::Matrix3d& m, const std::string& what,
                                double tolerance) {
  if (!m.allFinite()) throw Error(what + ": rotation matrix has a non-finite entry");
  const double err = (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > tolerance) {
    throw Error(what + ": not a rotation matrix (max |R^T R - I| = " + std::to_string(err) +
                ", expected <= " + std::to_string(tolerance) + ")");
  }
  if (m.determinant() < 0) throw Error(what + ": rotation matrix is a reflection (det < 0)");
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

}  // namespace sapmvs

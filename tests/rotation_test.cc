#include "sapmvs/block/rotation.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "sapmvs/block/camera.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The classic closed-form PATB matrix R = Rx(w) Ry(p) Rz(k), element by element
// as printed in photogrammetry textbooks (not a product of RotX/RotY/RotZ).
Eigen::Matrix3d HandOpk(double w, double p, double k) {
  const double cw = std::cos(w), sw = std::sin(w), cp = std::cos(p), sp = std::sin(p),
               ck = std::cos(k), sk = std::sin(k);
  Eigen::Matrix3d r;
  r << cp * ck, -cp * sk, sp,                                    //
      cw * sk + sw * sp * ck, cw * ck - sw * sp * sk, -sw * cp,  //
      sw * sk - cw * sp * ck, sw * ck + cw * sp * sk, cw * cp;
  return r;
}

// R = Ry(p) Rx(w) Rz(k), multiplied out by hand.
Eigen::Matrix3d HandPok(double p, double w, double k) {
  const double cw = std::cos(w), sw = std::sin(w), cp = std::cos(p), sp = std::sin(p),
               ck = std::cos(k), sk = std::sin(k);
  Eigen::Matrix3d r;
  r << cp * ck + sp * sw * sk, -cp * sk + sp * sw * ck, sp * cw,  //
      cw * sk, cw * ck, -sw,                                      //
      -sp * ck + cp * sw * sk, sp * sk + cp * sw * ck, cp * cw;
  return r;
}

struct UnitCase {
  AngleUnit unit;
  double per_radian;
};

void PrintTo(const UnitCase& u, std::ostream* os) { *os << ToString(u.unit); }

class AngleConventionTest : public ::testing::TestWithParam<UnitCase> {};

TEST_P(AngleConventionTest, MatchesHandComputedMatrices) {
  const UnitCase u = GetParam();
  const double triples[][3] = {{10, 20, 30}, {-5.5, 2.25, 179}, {0.3, -0.7, -101}, {45, 60, 200}};
  for (const auto& t : triples) {
    // The triple in degrees, expressed in the unit under test.
    const double a = t[0] * kPi / 180, b = t[1] * kPi / 180, c = t[2] * kPi / 180;
    const Eigen::Matrix3d opk = CameraToWorldFromAngles(
        a * u.per_radian, b * u.per_radian, c * u.per_radian, AngleOrder::kOmegaPhiKappa, u.unit);
    EXPECT_LT((opk - HandOpk(a, b, c)).cwiseAbs().maxCoeff(), 1e-12);
    const Eigen::Matrix3d pok = CameraToWorldFromAngles(
        a * u.per_radian, b * u.per_radian, c * u.per_radian, AngleOrder::kPhiOmegaKappa, u.unit);
    EXPECT_LT((pok - HandPok(a, b, c)).cwiseAbs().maxCoeff(), 1e-12);
    // The orders differ except in special cases.
    EXPECT_GT((opk - pok).cwiseAbs().maxCoeff(), 1e-3);
  }
}

INSTANTIATE_TEST_SUITE_P(Units, AngleConventionTest,
                         ::testing::Values(UnitCase{AngleUnit::kDegree, 180 / kPi},
                                           UnitCase{AngleUnit::kGon, 200 / kPi},
                                           UnitCase{AngleUnit::kRadian, 1.0}),
                         [](const auto& p) { return ToString(p.param.unit); });

TEST(AngleUnits, TwoHundredGonIsHalfATurn) {
  EXPECT_NEAR(ToRadians(200, AngleUnit::kGon), kPi, 1e-15);
  EXPECT_NEAR(ToRadians(180, AngleUnit::kDegree), kPi, 1e-15);
  EXPECT_NEAR(FromRadians(kPi, AngleUnit::kGon), 200, 1e-12);
  EXPECT_LT((CameraToWorldFromAngles(0, 0, 200, AngleOrder::kOmegaPhiKappa, AngleUnit::kGon) -
             CameraToWorldFromAngles(0, 0, 180, AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree))
                .cwiseAbs()
                .maxCoeff(),
            1e-14);
}

TEST(AngleUnits, ParsesSpellingsAndRejectsUnknown) {
  EXPECT_EQ(ParseAngleUnit("deg"), AngleUnit::kDegree);
  EXPECT_EQ(ParseAngleUnit("Degrees"), AngleUnit::kDegree);
  EXPECT_EQ(ParseAngleUnit("gon"), AngleUnit::kGon);
  EXPECT_EQ(ParseAngleUnit("rad"), AngleUnit::kRadian);
  EXPECT_EQ(ParseAngleOrder("omega-phi-kappa"), AngleOrder::kOmegaPhiKappa);
  EXPECT_EQ(ParseAngleOrder("POK"), AngleOrder::kPhiOmegaKappa);
  try {
    ParseAngleUnit("grads per second");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("'grads per second'"), std::string::npos);
  }
  EXPECT_THROW(ParseAngleOrder("kappa-phi-omega"), Error);
}

// Direction in which image +x (columns) points on the ground, for a camera
// looking down: the flight direction of a frame camera flown with x along track.
Eigen::Vector3d ImageXOnGround(const Camera& cam) {
  const Eigen::Vector2d pp(cam.intrinsics().cx, cam.intrinsics().cy);
  const Eigen::Vector3d a = cam.BackProject(pp, 1000),
                        b = cam.BackProject(pp + Eigen::Vector2d(10, 0), 1000);
  return (b - a).normalized();
}

TEST(LevelCamera, FlightDirectionFollowsKappa) {
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 399.5, 1000, 800);
  const Eigen::Vector3d center(5e5, 5.4e6, 1000);
  struct Case {
    double kappa_deg;
    Eigen::Vector3d heading;
  };
  const Case cases[] = {{0, {1, 0, 0}}, {180, {-1, 0, 0}}, {90, {0, 1, 0}}, {-90, {0, -1, 0}}};
  for (AngleOrder order : {AngleOrder::kOmegaPhiKappa, AngleOrder::kPhiOmegaKappa}) {
    for (const Case& c : cases) {
      const Camera cam =
          Camera::FromAngles(k, center, 0, 0, c.kappa_deg, order, AngleUnit::kDegree);
      EXPECT_LT((ImageXOnGround(cam) - c.heading).norm(), 1e-12) << "kappa " << c.kappa_deg;
      // Looking straight down.
      EXPECT_LT((cam.ViewingDirection() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
      // A ground point ahead along the heading lands right of the principal
      // point on the same row; one to the left of the track lands above it.
      const Eigen::Vector3d ground(center.x(), center.y(), 0);
      const Eigen::Vector2d ahead = cam.Project(ground + 100 * c.heading);
      EXPECT_NEAR(ahead.x(), k.cx + 100.0, 1e-9);
      EXPECT_NEAR(ahead.y(), k.cy, 1e-9);
      const Eigen::Vector3d left = Eigen::Vector3d::UnitZ().cross(c.heading);
      const Eigen::Vector2d l = cam.Project(ground + 100 * left);
      EXPECT_NEAR(l.x(), k.cx, 1e-9);
      EXPECT_NEAR(l.y(), k.cy - 100.0, 1e-9);
    }
  }
}

TEST(LevelCamera, PaperTable7KappaIsGonNotDegrees) {
  // Vaihingen (paper, Table 7): kappa = 199.3297 printed as "degree", but the
  // strip flies along -X only if it is read as gon.
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 399.5, 1000, 800);
  const Eigen::Vector3d c(497000, 5419000, 1000);
  const Camera gon =
      Camera::FromAngles(k, c, 0, 0, 199.3297, AngleOrder::kOmegaPhiKappa, AngleUnit::kGon);
  const Camera deg =
      Camera::FromAngles(k, c, 0, 0, 199.3297, AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  const Eigen::Vector3d minus_x(-1, 0, 0);
  const double gon_off = std::acos(ImageXOnGround(gon).dot(minus_x)) * 180 / kPi;
  const double deg_off = std::acos(ImageXOnGround(deg).dot(minus_x)) * 180 / kPi;
  EXPECT_NEAR(gon_off, 0.6033, 1e-3);  // 0.6703 gon = 0.6033 deg off -X
  EXPECT_GT(deg_off, 19.0);            // read as degrees it is 19.3 deg off
}

TEST(AngleRoundTrip, RecoversAnglesFromRotation) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> small(-80, 80), any(-179, 179);
  for (int i = 0; i < 200; ++i) {
    for (AngleOrder order : {AngleOrder::kOmegaPhiKappa, AngleOrder::kPhiOmegaKappa}) {
      for (AngleUnit unit : {AngleUnit::kDegree, AngleUnit::kGon, AngleUnit::kRadian}) {
        const double s = FromRadians(kPi / 180, unit);
        const Eigen::Vector3d a(any(rng) * s, small(rng) * s, any(rng) * s);
        const Eigen::Matrix3d r = WorldToCameraFromAngles(a[0], a[1], a[2], order, unit);
        const Eigen::Vector3d back = AnglesFromWorldToCamera(r, order, unit);
        EXPECT_LT((back - a).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, s));
      }
    }
  }
}

TEST(CheckedRotation, RejectsNonRotations) {
  EXPECT_THROW(CheckedRotation(Eigen::Matrix3d::Identity() * 2, "R"), Error);
  EXPECT_THROW(CheckedRotation(Eigen::Vector3d(1, 1, -1).asDiagonal(), "R"), Error);
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 1) = std::nan("");
  EXPECT_THROW(CheckedRotation(nan, "R"), Error);
  const Eigen::Matrix3d r = RotZ(0.3) * RotX(0.2);
  EXPECT_LT((CheckedRotation(r, "R") - r).norm(), 1e-12);
}

}  // namespace
}  // namespace sapmvs

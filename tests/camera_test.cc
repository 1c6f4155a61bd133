#include "sapmvs/block/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <random>

#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

Camera RandomCamera(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(-40, 40), kappa(-180, 180), pos(-500, 500);
  Intrinsics k = Intrinsics::FromPixels(900 + pos(rng) * 0.2, 905 + pos(rng) * 0.2,
                                        640 + pos(rng) * 0.01, 480 + pos(rng) * 0.01, 1279, 961);
  return Camera::FromAngles(
      k, Eigen::Vector3d(5e5 + pos(rng), 5.4e6 + pos(rng), 800 + pos(rng) * 0.1), angle(rng),
      angle(rng), kappa(rng), AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
}

TEST(Intrinsics, FromFocalAndPixelSize) {
  // Canon EOS 400D-like: 24 mm lens, 5.7 um pixels.
  const Intrinsics k = Intrinsics::FromFocalAndPixel(24, 5.7, 3888, 2592);
  EXPECT_NEAR(k.fx, 24 / 0.0057, 1e-9);
  EXPECT_NEAR(k.fy, 24 / 0.0057, 1e-9);
  EXPECT_DOUBLE_EQ(k.cx, 1943.5);
  EXPECT_DOUBLE_EQ(k.cy, 1295.5);
}

TEST(Intrinsics, FromFocalAndSensorMatchesNgiConfig) {
  // NGI DMC, 12x downsampled: 120 mm, 92.16 x 165.888 mm, 640 x 1152 px.
  const Intrinsics k = Intrinsics::FromFocalAndSensor(120, 92.16, 165.888, 640, 1152);
  EXPECT_NEAR(k.fx, 833.333333333, 1e-6);
  EXPECT_NEAR(k.fy, 833.333333333, 1e-6);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 575.5);
}

TEST(Intrinsics, PrincipalOffsetIsPhotogrammetricYUp) {
  // +0.1 mm in x moves cx right; +0.1 mm in y (up) moves cy to a smaller row.
  const Intrinsics k = Intrinsics::FromFocalAndPixel(50, 10, 101, 81, Eigen::Vector2d(0.1, 0.1));
  EXPECT_NEAR(k.cx, 50 + 10, 1e-9);
  EXPECT_NEAR(k.cy, 40 - 10, 1e-9);
}

TEST(Intrinsics, RejectsBadValues) {
  EXPECT_THROW(Intrinsics::FromFocalAndPixel(0, 5, 100, 100), Error);
  EXPECT_THROW(Intrinsics::FromFocalAndPixel(24, std::nan(""), 100, 100), Error);
  EXPECT_THROW(Intrinsics::FromFocalAndSensor(24, 10, 10, 0, 100), Error);
  EXPECT_THROW(Intrinsics::FromPixels(-1, 1, 0, 0, 10, 10).Validate("cam"), Error);
}

TEST(Intrinsics, ScaledKeepsPixelCentreConvention) {
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 399.5, 1000, 800);
  const Intrinsics h = k.Scaled(0.5);
  EXPECT_EQ(h.width, 500);
  EXPECT_EQ(h.height, 400);
  EXPECT_DOUBLE_EQ(h.fx, 500);
  EXPECT_DOUBLE_EQ(h.cx, 249.5);  // still the image centre
  EXPECT_DOUBLE_EQ(h.cy, 199.5);
}

TEST(Camera, ProjectBackProjectRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1279), v(0, 961), d(300, 1500);
  for (int i = 0; i < 100; ++i) {
    const Camera cam = RandomCamera(rng);
    const Eigen::Vector2d uv(u(rng), v(rng));
    const double depth = d(rng);
    const Eigen::Vector3d x = cam.BackProject(uv, depth);
    EXPECT_NEAR(cam.Depth(x), depth, 1e-8);
    EXPECT_LT((cam.Project(x) - uv).norm(), 1e-7);
    // The ray through uv points at x.
    EXPECT_LT((cam.Ray(uv) - (x - cam.center()).normalized()).norm(), 1e-9);
  }
}

TEST(Camera, BehindTheCameraIsNaN) {
  std::mt19937 rng(8);
  const Camera cam = RandomCamera(rng);
  const Eigen::Vector3d behind = cam.center() - 10 * cam.ViewingDirection();
  EXPECT_TRUE(cam.Project(behind).array().isNaN().all());
}

TEST(Camera, ProjectionMatrixAgreesWithProject) {
  std::mt19937 rng(9);
  const Camera cam = RandomCamera(rng);
  const Eigen::Vector3d x = cam.BackProject({100, 200}, 700);
  const Eigen::Vector3d h = cam.ProjectionMatrix() * x.homogeneous();
  EXPECT_LT((h.hnormalized() - cam.Project(x)).norm(), 1e-6);
}

TEST(Camera, DecomposesProjectionMatricesOfAnyScaleAndSign) {
  std::mt19937 rng(11);
  for (int i = 0; i < 50; ++i) {
    const Camera cam = RandomCamera(rng);
    for (double scale : {1.0, -3.5e-4, 12.0}) {
      const Camera back =
          Camera::FromProjectionMatrix(scale * cam.ProjectionMatrix(), cam.width(), cam.height());
      EXPECT_LT((back.center() - cam.center()).norm(), 1e-6);
      EXPECT_LT((back.rotation() - cam.rotation()).cwiseAbs().maxCoeff(), 1e-9);
      EXPECT_NEAR(back.intrinsics().fx, cam.intrinsics().fx, 1e-7);
      EXPECT_NEAR(back.intrinsics().fy, cam.intrinsics().fy, 1e-7);
      EXPECT_NEAR(back.intrinsics().cx, cam.intrinsics().cx, 1e-7);
      EXPECT_NEAR(back.intrinsics().cy, cam.intrinsics().cy, 1e-7);
    }
  }
}

TEST(Camera, RejectsSingularOrSkewedProjectionMatrices) {
  Eigen::Matrix<double, 3, 4> p = Eigen::Matrix<double, 3, 4>::Zero();
  p(0, 0) = p(1, 1) = 1;
  EXPECT_THROW(Camera::FromProjectionMatrix(p, 10, 10), Error);
  Eigen::Matrix<double, 3, 4> skew;
  skew << 1000, 50, 320, 0, 0, 1000, 240, 0, 0, 0, 1, 0;
  EXPECT_THROW(Camera::FromProjectionMatrix(skew, 640, 480), Error);
}

TEST(Camera, NadirFootprintIsDepthOverFocal) {
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 399.5, 1000, 800);
  const Camera cam =
      Camera::FromAngles(k, {0, 0, 700}, 0, 0, 0, AngleOrder::kOmegaPhiKappa, AngleUnit::kDegree);
  EXPECT_NEAR(cam.Footprint({0, 0, 0}, Eigen::Vector3d::UnitZ()), 0.7, 1e-12);
  EXPECT_NEAR(cam.FootprintFacing({0, 0, 0}), 0.7, 1e-12);
  // A 60 deg slope facing away stretches the footprint by 1/sqrt(cos 60).
  const Eigen::Vector3d n(std::sin(M_PI / 3), 0, std::cos(M_PI / 3));
  EXPECT_NEAR(cam.Footprint({0, 0, 0}, n), 0.7 / std::sqrt(0.5), 1e-12);
}

TEST(Camera, TranslatedKeepsImageCoordinates) {
  std::mt19937 rng(12);
  const Camera cam = RandomCamera(rng);
  const Eigen::Vector3d origin(5e5, 5.4e6, 300);
  const Camera local = cam.Translated(origin);
  const Eigen::Vector3d x = cam.BackProject({321, 123}, 650);
  EXPECT_LT((local.Project(x - origin) - cam.Project(x)).norm(), 1e-7);
}

TEST(Distortion, MatchesOpenCvProjectPoints) {
  std::mt19937 rng(13);
  Camera cam = RandomCamera(rng);
  Intrinsics k = cam.intrinsics();
  k.distortion = {-0.264, 0.1019, -0.0258, 0.00073, 0.00026};
  cam = cam.WithIntrinsics(k);
  std::vector<cv::Point3d> pts;
  std::vector<Eigen::Vector3d> eig;
  std::uniform_real_distribution<double> u(0, 1279), v(0, 961);
  for (int i = 0; i < 50; ++i) {
    eig.push_back(cam.BackProject({u(rng), v(rng)}, 500));
    const Eigen::Vector3d c = cam.ToCamera(eig.back());
    pts.emplace_back(c.x(), c.y(), c.z());
  }
  const cv::Mat kk = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << k.distortion.k1, k.distortion.k2, k.distortion.p1,
                        k.distortion.p2, k.distortion.k3);
  std::vector<cv::Point2d> out;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), kk, dist, out);
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d p = cam.ProjectDistorted(eig[i]);
    EXPECT_NEAR(p.x(), out[i].x, 1e-6);
    EXPECT_NEAR(p.y(), out[i].y, 1e-6);
  }
}

TEST(Undistort, PinholeImageMatchesDistortedProjection) {
  // A smooth synthetic scene: intensity is a function of the undistorted
  // pixel. Rendering it through the distortion and undistorting must give the
  // function back, away from the border.
  Intrinsics k = Intrinsics::FromPixels(400, 400, 160.3, 119.7, 321, 241);
  k.distortion = {-0.25, 0.08, 0, 0.001, -0.0005};
  auto f = [](double x, double y) { return 128 + 60 * std::sin(x / 9.0) * std::cos(y / 13.0); };
  // Distorted image: pixel (u, v) sees the undistorted point that maps to it.
  cv::Mat src(k.height, k.width, CV_8UC3);
  const cv::Mat kk = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << k.distortion.k1, k.distortion.k2, k.distortion.p1,
                        k.distortion.p2, k.distortion.k3);
  std::vector<cv::Point2d> raw, und;
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) raw.emplace_back(u, v);
  cv::undistortPoints(raw, und, kk, dist, cv::noArray(), kk);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const cv::Point2d& p = und[static_cast<size_t>(v) * k.width + u];
      const auto g = cv::saturate_cast<uchar>(f(p.x, p.y));
      src.at<cv::Vec3b>(v, u) = cv::Vec3b(g, g, g);
    }
  }
  const cv::Mat out = Undistort(src, k);
  double err = 0;
  int n = 0;
  for (int v = 40; v < k.height - 40; ++v) {
    for (int u = 40; u < k.width - 40; ++u) {
      err += std::abs(out.at<cv::Vec3b>(v, u)[0] - f(u, v));
      ++n;
    }
  }
  EXPECT_LT(err / n, 1.5) << "mean abs error in grey levels";
  // Without undistortion the same comparison is clearly worse.
  double raw_err = 0;
  for (int v = 40; v < k.height - 40; ++v)
    for (int u = 40; u < k.width - 40; ++u)
      raw_err += std::abs(src.at<cv::Vec3b>(v, u)[0] - f(u, v));
  EXPECT_GT(raw_err / n, 3 * err / n);
}

}  // namespace
}  // namespace sapmvs

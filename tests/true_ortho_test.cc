// The true orthophoto: a DSM's holes filled where the surface encloses them,
// its objects found, each image's depth buffer hiding what lies behind a
// box, and the ortho of a box on textured ground coloured from the image that
// sees each cell: the ground behind the box from the view that sees past it,
// the roof on its footprint, the ground as its texture.
#include "sapmvs/ortho/true_ortho.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "ortho/ortho_depth_buffer.h"
#include "ortho/ortho_surface.h"
#include "sapmvs/run/cloud_dsm.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

constexpr double kBoxMin = 25, kBoxMax = 35, kBoxTop = 10;  // m, on a 60 m square

GeoRaster FlatDsm(int side, double cell, float height) {
  GeoRaster r;
  r.width = r.height = side;
  r.cell_size = cell;
  r.origin_x = 0;
  r.origin_y = side * cell;
  r.values.assign(static_cast<size_t>(side) * side, height);
  return r;
}

// 1 m cells, ground at 0, the box's cells at its top.
GeoRaster BoxDsm() {
  GeoRaster r = FlatDsm(60, 1.0, 0);
  for (int row = 0; row < 60; ++row) {
    for (int col = 0; col < 60; ++col) {
      const Eigen::Vector2d p = r.CellCenter(col, row);
      if (p.x() > kBoxMin && p.x() < kBoxMax && p.y() > kBoxMin && p.y() < kBoxMax)
        r.at(col, row) = kBoxTop;
    }
  }
  return r;
}

// Looking straight down from `center`, 500 x 500 px, f = 50 px: 0.8 m
// pixels on the ground from 40 m, 0.5 m cells of the ortho.
Camera NadirCamera(const Eigen::Vector3d& center) {
  Eigen::Matrix3d r_wc;
  r_wc << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  return Camera(Intrinsics::FromPixels(50, 50, 249.5, 249.5, 500, 500), r_wc, center);
}

// RGB of the ground, smooth enough for bilinear sampling at 1 px.
Eigen::Vector3d GroundColour(double x, double y) {
  return {60 + 40 * std::sin(x / 2), 160 + 40 * std::cos(y / 2.5), 60};
}
const Eigen::Vector3d kRoof(220, 40, 40), kWall(40, 40, 220);

// What `camera` sees of the box scene (slab test against the box).
Eigen::Vector3d Trace(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(kBoxMin, kBoxMin, 0), hi(kBoxMax, kBoxMax, kBoxTop);
  double t0 = 0, t1 = 1e9;
  int axis = -1;
  for (int a = 0; a < 3; ++a) {
    const double ta = (lo[a] - o[a]) / d[a], tb = (hi[a] - o[a]) / d[a];
    const double near = std::min(ta, tb), far = std::max(ta, tb);
    if (near > t0) {
      t0 = near;
      axis = a;
    }
    t1 = std::min(t1, far);
  }
  if (t0 <= t1 && axis >= 0) return axis == 2 ? kRoof : kWall;
  const Eigen::Vector3d g = o - o.z() / d.z() * d;
  return GroundColour(g.x(), g.y());
}

BlockImage RenderImage(const std::filesystem::path& dir, const std::string& name,
                       const Camera& camera) {
  cv::Mat bgr(camera.height(), camera.width(), CV_8UC3);
  for (int v = 0; v < camera.height(); ++v) {
    for (int u = 0; u < camera.width(); ++u) {
      const Eigen::Vector3d c = Trace(camera.center(), camera.Ray({u, v}));
      bgr.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<uint8_t>(std::lround(c.z())),
                                          static_cast<uint8_t>(std::lround(c.y())),
                                          static_cast<uint8_t>(std::lround(c.x())));
    }
  }
  BlockImage image;
  image.name = name;
  image.path = dir / (name + ".png");
  image.camera_name = "c";
  image.camera = camera;
  cv::imwrite(image.path.string(), bgr);
  return image;
}

Eigen::Vector3d OrthoColour(const TrueOrtho& o, double x, double y, bool* filled) {
  const size_t i = RasterCellIndex(o.grid, x, y);
  *filled = o.rgba[4 * i + 3] == 255;
  return {double(o.rgba[4 * i]), double(o.rgba[4 * i + 1]), double(o.rgba[4 * i + 2])};
}

TEST(OrthoSurfaceTest, FillsTheHolesTheSurfaceEncloses) {
  GeoRaster dsm = FlatDsm(9, 1.0, 5);
  for (int c = 0; c < 9; ++c) dsm.at(c, 0) = 5 + c;            // a rim of different heights
  dsm.at(4, 4) = dsm.at(5, 4) = dsm.at(4, 5) = std::nanf("");  // enclosed
  dsm.at(0, 8) = dsm.at(1, 8) = std::nanf("");                 // open to the edge
  EXPECT_EQ(FillEnclosedHoles(&dsm), 3);
  EXPECT_EQ(dsm.at(4, 4), 5.f);
  EXPECT_EQ(dsm.at(4, 5), 5.f);
  EXPECT_TRUE(dsm.IsEmpty(0, 8));
  EXPECT_TRUE(dsm.IsEmpty(1, 8));
}

TEST(OrthoSurfaceTest, AHoleKeepsItsRimsHeightsNextToTheRim) {
  // Ground at 0 west of column 3, a roof at 10 east of column 8, and
  // between them five empty columns: a roof's edge and the ground at its
  // foot that matched nothing.
  GeoRaster dsm = FlatDsm(12, 1.0, 0);
  for (int r = 0; r < 12; ++r) {
    for (int c = 8; c < 12; ++c) dsm.at(c, r) = 10;
  }
  for (int r = 2; r < 10; ++r) {
    for (int c = 3; c < 8; ++c) dsm.at(c, r) = std::nanf("");
  }
  EXPECT_EQ(FillEnclosedHoles(&dsm), 40);
  EXPECT_EQ(dsm.at(3, 5), 0.f);   // beside the ground
  EXPECT_EQ(dsm.at(7, 5), 10.f);  // beside the roof
  EXPECT_EQ(dsm.at(6, 5), 0.f);   // two cells from the roof: the rim's low height
}

TEST(OrthoSurfaceTest, ABoxIsOneObjectAndFlatGroundNone) {
  const OrthoSurface flat = MakeOrthoSurface(FlatDsm(60, 1.0, 3), 0.5, 1.0, 1.0);
  EXPECT_EQ(flat.objects, 0);
  EXPECT_EQ(flat.grid.width, 120);
  EXPECT_FLOAT_EQ(flat.grid.at(7, 9), 3.f);
  const OrthoSurface box = MakeOrthoSurface(BoxDsm(), 0.5, 1.0, 1.0);
  EXPECT_EQ(box.objects, 1);
  // The roof's middle, far from its edges, is part of it; open ground not.
  EXPECT_EQ(box.ObjectAt(60, 60), 0);
  EXPECT_EQ(box.ObjectAt(10, 10), -1);
  // Heights across the box's wall: the nearest cell's, not a slope that
  // would lean the roof over the ground (cell centres at 24.75 and 25.25 m
  // east, between the DSM's at 24.5 and 25.5).
  EXPECT_FLOAT_EQ(box.grid.at(49, 59), 0.f);
  EXPECT_FLOAT_EQ(box.grid.at(50, 59), static_cast<float>(kBoxTop));
  // On one surface, bilinear: a ramp of 1 per cell.
  GeoRaster ramp = FlatDsm(9, 1.0, 0);
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 9; ++c) ramp.at(c, r) = static_cast<float>(c) * 0.5f;
  }
  EXPECT_FLOAT_EQ(MakeOrthoSurface(ramp, 0.5, 1.0, 1.0).grid.at(6, 4), 1.375f);
}

TEST(OrthoDepthBufferTest, TheBoxHidesTheGroundBehindIt) {
  const GeoRaster dsm = BoxDsm();
  // Low and west of the box: its west wall hides the ground just east of it.
  const Camera camera = NadirCamera({0, 30, 20});
  const OrthoDepthBuffer depth(camera, dsm, {0, 0, 60, 60}, WallQuads(dsm, 1.0), 0.5);
  Eigen::Vector2d uv;
  EXPECT_TRUE(depth.Sees({15, 30, 0}, &uv));          // before the box
  EXPECT_TRUE(depth.Sees({30, 30, kBoxTop}, &uv));    // its roof
  EXPECT_TRUE(depth.Sees({24.5, 30, 0}, &uv));        // the ground cell at the wall, in front
  EXPECT_TRUE(depth.Sees({25.5, 30, kBoxTop}, &uv));  // the roof's edge cell
  EXPECT_FALSE(depth.Sees({38, 30, 0}, &uv));         // behind it
  // From above the box's east half, the ray from the ground at 21.3 m
  // meets the west wall 0.5 m under the roof: drawn as a slope from the
  // ground's cell centre up to the roof's, the wall would lack the roof's
  // last half cell, and the ray would pass over it. (The camera puts the
  // point on a pixel's centre, where the depth is drawn.)
  const Camera above = NadirCamera({36.9, 30.4, 40});
  const OrthoDepthBuffer over(above, dsm, {0, 0, 60, 60}, WallQuads(dsm, 1.0), 0.5);
  EXPECT_FALSE(over.Sees({21.3, 30, 0}, &uv));
  EXPECT_TRUE(over.Sees({25.5, 30, kBoxTop}, &uv));
  EXPECT_TRUE(depth.Sees({58, 50, 0}, &uv));  // beside its shadow
  EXPECT_NEAR(uv.x(), camera.Project({58, 50, 0}).x(), 1e-9);
}

class TrueOrthoTest : public test::ScratchTest {};

TEST_F(TrueOrthoTest, TakesEachCellFromAViewThatSeesIt) {
  Block block;
  // A: above the box's east half, the most direct view of the ground just
  // west of the box, which the box hides from it. B: far west, sees it.
  block.images.push_back(RenderImage(dir_, "a", NadirCamera({37, 30, 40})));
  block.images.push_back(RenderImage(dir_, "b", NadirCamera({-20, 30, 40})));
  OrthoOptions options;
  const TrueOrtho ortho = MakeTrueOrtho(block, BoxDsm(), 0, options, 0.5);
  EXPECT_EQ(ortho.grid.width, 120);
  EXPECT_EQ(ortho.objects, 1);
  EXPECT_EQ(ortho.images_used, 2);
  // The ground in A's shadow, from where A sees the roof's edge: its
  // texture, from B; not the wall A sees there. (Nearer the wall than
  // 24.5 m, B's pixels of 0.8 m on the ground hold the wall behind the
  // ground too.)
  int checked = 0;
  for (double x = 21.25; x < 24.5; x += 0.5) {
    for (double y = 28.25; y < 32; y += 0.5) {
      bool filled = false;
      const Eigen::Vector3d c = OrthoColour(ortho, x, y, &filled);
      ASSERT_TRUE(filled) << x << " " << y;
      EXPECT_LT((c - GroundColour(x, y)).cwiseAbs().maxCoeff(), 12)
          << x << " " << y << ": " << c.transpose();
      ++checked;
    }
  }
  EXPECT_EQ(checked, 56);
  // The roof on its footprint, away from its edges.
  for (double x = 26.25; x < 34; x += 1) {
    bool filled = false;
    const Eigen::Vector3d c = OrthoColour(ortho, x, 30.25, &filled);
    ASSERT_TRUE(filled);
    EXPECT_LT((c - kRoof).cwiseAbs().maxCoeff(), 12) << x << ": " << c.transpose();
  }
  // Open ground: its texture; the median error, as seams blend two views'
  // samples of the same colour.
  std::vector<double> errors;
  for (double x = 2.25; x < 58; x += 1) {
    for (double y = 2.25; y < 20; y += 1) {
      bool filled = false;
      const Eigen::Vector3d c = OrthoColour(ortho, x, y, &filled);
      ASSERT_TRUE(filled);
      errors.push_back((c - GroundColour(x, y)).cwiseAbs().maxCoeff());
    }
  }
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 3);
}

TEST_F(TrueOrthoTest, RefusesBadOptionsAndAGridTooLarge) {
  Block block;
  OrthoOptions options;
  options.blend_cells = 8;
  EXPECT_THROW(MakeTrueOrtho(block, BoxDsm(), 0, options, 0.5), Error);
  try {
    MakeTrueOrtho(block, BoxDsm(), 0, OrthoOptions{}, 1e-4);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--ortho-cell"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sapmvs

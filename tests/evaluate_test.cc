#include "sapmvs/evaluate/evaluate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "evaluate/dsm_reference.h"
#include "evaluate/lidar_reference.h"
#include "sapmvs/io/las_io.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/error.h"
#include "test_util.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;
using Points = std::vector<Eigen::Vector3d>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Eigen::Vector2d kUtm(512000, 5405000);

// A plane z = 300 + gx (x - x0) + gy (y - y0), in local terms so that the
// heights stay exact whatever the offset.
struct Plane {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double gx = 0, gy = 0;
  double operator()(double x, double y) const {
    return 300 + gx * (x - origin.x()) + gy * (y - origin.y());
  }
};

// LiDAR nodes origin + (i s, j s), i, j = 0..n-1, on `plane`.
Points GridLidar(const Plane& plane, double s, int n) {
  Points p;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = plane.origin.x() + i * s, y = plane.origin.y() + j * s;
      p.emplace_back(x, y, plane(x, y));
    }
  }
  return p;
}

EvaluateOptions Options(double radius = 0, std::vector<double> drop_above = {}) {
  EvaluateOptions o;
  o.cloud = "cloud.ply";
  o.reference = "lidar.las";
  o.radius = radius;
  o.drop_above = std::move(drop_above);
  o.quiet = true;
  return o;
}

TEST(EvaluateRow, StatisticsOfAHandMadeSet) {
  const std::vector<double> dz = {0.5, -1.5, 3, kNaN, -0.2, 10};
  const ErrorRow all = ComputeErrorRow(dz, 1.0);
  EXPECT_TRUE(std::isinf(all.threshold));
  EXPECT_EQ(all.checkpoints, 5);
  EXPECT_EQ(all.dropped, 0);
  EXPECT_DOUBLE_EQ(all.rmse, std::sqrt((0.25 + 2.25 + 9 + 0.04 + 100) / 5));
  EXPECT_DOUBLE_EQ(all.max_abs, 10);
  EXPECT_DOUBLE_EQ(all.mean, (0.5 - 1.5 + 3 - 0.2 + 10) / 5);
  EXPECT_DOUBLE_EQ(all.within, 2.0 / 5);
  EXPECT_DOUBLE_EQ(all.median_abs, 1.5);  // of 0.2 0.5 1.5 3 10
  const ErrorRow kept = ComputeErrorRow(dz, 1.0, 2.0);
  EXPECT_EQ(kept.checkpoints, 3);
  EXPECT_EQ(kept.dropped, 2);
  EXPECT_DOUBLE_EQ(kept.rmse, std::sqrt((0.25 + 2.25 + 0.04) / 3));
  EXPECT_DOUBLE_EQ(kept.max_abs, 1.5);
  EXPECT_DOUBLE_EQ(kept.median_abs, 0.5);  // of 0.2 0.5 1.5
  // An even count: the mean of the middle two (0.5 and 1.5 of 0.2 0.5 1.5 3).
  EXPECT_DOUBLE_EQ(ComputeErrorRow(dz, 1.0, 3.0).median_abs, 1.0);
  // |dz| == T is kept: the paper drops |dz| > T.
  EXPECT_EQ(ComputeErrorRow(dz, 1.0, 3.0).checkpoints, 4);
  const ErrorRow none = ComputeErrorRow({kNaN}, 1.0);
  EXPECT_EQ(none.checkpoints, 0);
  EXPECT_TRUE(std::isnan(none.rmse));
  EXPECT_TRUE(std::isnan(none.median_abs));
}

// Cloud points at the centres of the LiDAR grid cells, away from its border,
// each dz = offset + (+sigma, -sigma, ...): the neighbours within d of a cell
// centre are symmetric about it, so their mean is the plane there and the
// RMSE is sqrt(offset^2 + sigma^2).
void ExpectAnalyticPlane(const Eigen::Vector2d& origin) {
  const Plane plane{origin, 0.1, -0.05};
  const double s = 0.5, offset = 0.3, sigma = 0.2;
  const Points lidar = GridLidar(plane, s, 41);
  Points cloud;
  for (int j = 4; j < 36; ++j) {
    for (int i = 4; i < 36; ++i) {
      const double x = origin.x() + (i + 0.5) * s, y = origin.y() + (j + 0.5) * s;
      cloud.emplace_back(x, y, plane(x, y) + offset + (cloud.size() % 2 ? -sigma : sigma));
    }
  }
  const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options(1.0));
  ASSERT_EQ(r.rows.size(), 1u);
  EXPECT_EQ(r.without_reference, 0);
  EXPECT_EQ(r.rows[0].checkpoints, 32 * 32);
  EXPECT_NEAR(r.rows[0].rmse, std::hypot(offset, sigma), 1e-9);
  EXPECT_NEAR(r.rows[0].mean, offset, 1e-9);
  EXPECT_NEAR(r.rows[0].max_abs, offset + sigma, 1e-9);
  EXPECT_DOUBLE_EQ(r.rows[0].within, 1.0);
}

TEST(EvaluateLidar, TiltedPlaneWithOffsetAndNoiseGivesTheAnalyticRmse) {
  ExpectAnalyticPlane({0, 0});
}

TEST(EvaluateLidar, UtmCoordinatesGiveTheSameAnswer) { ExpectAnalyticPlane(kUtm); }

TEST(EvaluateLidar, GaussianNoiseRmseMatchesAnIndependentSum) {
  std::mt19937 rng(42);
  std::normal_distribution<double> noise(0.0, 0.15);
  std::uniform_real_distribution<double> u(2, 18);
  const Plane flat{kUtm, 0, 0};
  const Points lidar = GridLidar(flat, 0.5, 41);
  Points cloud;
  double sum2 = 0, sum = 0;
  for (int i = 0; i < 5001; ++i) {
    const double dz = -0.25 + noise(rng);
    sum += dz;
    sum2 += dz * dz;
    cloud.emplace_back(kUtm.x() + u(rng), kUtm.y() + u(rng), 300 + dz);
  }
  const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options());
  EXPECT_EQ(r.rows[0].checkpoints, 5001);
  EXPECT_NEAR(r.rows[0].rmse, std::sqrt(sum2 / 5001), 1e-12);
  EXPECT_NEAR(r.rows[0].mean, sum / 5001, 1e-12);
}

TEST(EvaluateLidar, PseudoErrorThresholdsDropExactCounts) {
  const Plane flat{kUtm, 0, 0};
  const Points lidar = GridLidar(flat, 0.5, 41);
  // 100 points at +0.1, 10 at +3, 5 at -7, 2 at +20: T = 5 drops 7, T = 10 drops 2.
  const std::vector<std::pair<int, double>> groups = {{100, 0.1}, {10, 3}, {5, -7}, {2, 20}};
  Points cloud;
  for (const auto& [n, dz] : groups) {
    for (int i = 0; i < n; ++i) {
      cloud.emplace_back(kUtm.x() + 2 + 0.13 * cloud.size(), kUtm.y() + 10, 300 + dz);
    }
  }
  const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options(0, {5, 10}));
  ASSERT_EQ(r.rows.size(), 3u);
  EXPECT_EQ(r.rows[0].checkpoints, 117);
  EXPECT_EQ(r.rows[1].threshold, 5);
  EXPECT_EQ(r.rows[1].checkpoints, 110);
  EXPECT_EQ(r.rows[1].dropped, 7);
  EXPECT_EQ(r.rows[2].checkpoints, 115);
  EXPECT_EQ(r.rows[2].dropped, 2);
  EXPECT_NEAR(r.rows[1].rmse, std::sqrt((100 * 0.01 + 10 * 9.0) / 110), 1e-9);
  EXPECT_NEAR(r.rows[1].within, 100.0 / 110, 1e-12);
  EXPECT_NEAR(r.rows[2].max_abs, 7, 1e-9);
}

TEST(EvaluateLidar, PointsOutsideTheCoverageAreCountedNotDropped) {
  const Plane flat{kUtm, 0, 0};
  const Points lidar = GridLidar(flat, 0.5, 101);  // covers 0..50 from the origin
  Points cloud;
  for (int i = 0; i < 40; ++i) cloud.emplace_back(kUtm.x() + 1 + i, kUtm.y() + 25, 300.5);
  for (int i = 0; i < 13; ++i) cloud.emplace_back(kUtm.x() + 51.5, kUtm.y() + 2 * i, 300);
  // Exactly d from the edge column (x = 50): a neighbour, as documented.
  cloud.emplace_back(kUtm.x() + 51, kUtm.y() + 20, 301);
  const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options(1.0));
  EXPECT_EQ(r.cloud_points, 54);
  EXPECT_EQ(r.without_reference, 13);
  EXPECT_EQ(r.rows[0].checkpoints, 41);
  EXPECT_NEAR(r.rows[0].max_abs, 1.0, 1e-12);
  for (size_t i = 40; i < 53; ++i) EXPECT_TRUE(std::isnan(r.dz[i])) << i;
}

TEST(EvaluateLidar, MeanHeightsMatchABruteForceSearchAtUtmCoordinates) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 30), h(-5, 5);
  Points lidar, queries;
  for (int i = 0; i < 4000; ++i) {
    lidar.emplace_back(kUtm.x() + u(rng), kUtm.y() + u(rng), 250 + h(rng));
  }
  for (int i = 0; i < 2000; ++i) {
    queries.emplace_back(kUtm.x() - 2 + 1.15 * u(rng), kUtm.y() - 2 + 1.15 * u(rng), 0);
  }
  const double radius = 0.6;
  const std::vector<double> got = LidarReference(lidar).MeanHeights(queries, radius);
  int with = 0, without = 0;
  for (size_t q = 0; q < queries.size(); ++q) {
    double sum = 0;
    int n = 0;
    for (const Eigen::Vector3d& p : lidar) {
      if ((p.head<2>() - queries[q].head<2>()).squaredNorm() <= radius * radius) {
        sum += p.z();
        ++n;
      }
    }
    if (n == 0) {
      EXPECT_TRUE(std::isnan(got[q])) << q;
      ++without;
    } else {
      EXPECT_NEAR(got[q], sum / n, 1e-9) << q;
      ++with;
    }
  }
  EXPECT_GT(with, 1000);  // both branches exercised
  EXPECT_GT(without, 20);
}

TEST(EvaluateLidar, TightRadiusAtUtmCoordinatesFindsTheRightFourPoints) {
  // A steep plane and d = 0.15 on a 0.1 grid: a cell centre has exactly four
  // neighbours, whose mean is the plane there. XY rounded to float32 (0.5 m
  // steps at Y ~ 5.4e6) would pick other points and miss by metres.
  const Plane steep{kUtm, 2.0, -1.5};
  const Points lidar = GridLidar(steep, 0.1, 60);
  Points cloud;
  for (int j = 5; j < 55; ++j) {
    for (int i = 5; i < 55; ++i) {
      const double x = kUtm.x() + (i + 0.5) * 0.1, y = kUtm.y() + (j + 0.5) * 0.1;
      cloud.emplace_back(x, y, steep(x, y) + 0.003 + (cloud.size() % 2 ? -0.001 : 0.001));
    }
  }
  const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options(0.15));
  EXPECT_EQ(r.without_reference, 0);
  EXPECT_NEAR(r.rows[0].rmse, std::hypot(0.003, 0.001), 1e-9);
}

TEST(EvaluateLidar, DefaultRadiusComesFromTheGridSpacing) {
  for (double s : {0.5, 0.3}) {
    SCOPED_TRACE(s);
    Points lidar = GridLidar(Plane{kUtm, 0, 0}, s, 50);
    // A second return at every node (same XY, other Z) must not halve it.
    const size_t n = lidar.size();
    for (size_t i = 0; i < n; i += 3) lidar.push_back(lidar[i] + Eigen::Vector3d(0, 0, -4));
    EXPECT_NEAR(LidarReference(lidar).MedianSpacing(), s, 1e-9);
    const Points cloud = {Eigen::Vector3d(kUtm.x() + 5.01, kUtm.y() + 5.02, 300)};
    const EvaluationReport r = EvaluateAgainstLidar(cloud, lidar, Options());
    EXPECT_NEAR(r.spacing, s, 1e-9);
    EXPECT_NEAR(r.radius, kRadiusPerSpacing * s, 1e-9);
    EXPECT_NE(r.radius_note.find("median nearest-neighbour XY spacing"), std::string::npos);
    EXPECT_EQ(EvaluateAgainstLidar(cloud, lidar, Options(0.7)).radius_note, "given with --radius");
  }
}

TEST(EvaluateLidar, OneDistinctXyNeedsAGivenRadius) {
  const Points lidar = {{1, 2, 3}, {1, 2, 4}};
  EXPECT_THROW(EvaluateAgainstLidar({{1, 2, 3}}, lidar, Options()), Error);
  EXPECT_EQ(EvaluateAgainstLidar({{1, 2, 3}}, lidar, Options(1)).rows[0].mean, -0.5);
}

// A 4 x 3 DSM of 0.5 cells at UTM coordinates; values chosen so that the
// means below are exact in binary.
GeoRaster SmallDsm() {
  GeoRaster d;
  d.width = 4;
  d.height = 3;
  d.origin_x = kUtm.x();
  d.origin_y = kUtm.y();
  d.cell_size = 0.5;
  d.values = {10, 11, 12, 13,  //
              14, 15, 16, 17,  //
              18, 19, 20, -9999};
  d.nodata = -9999;
  return d;
}

TEST(EvaluateDsm, BilinearIsExactAtCentresAndCorners) {
  const GeoRaster d = SmallDsm();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector2d p = d.CellCenter(c, r);
      if (d.IsEmpty(c, r)) {
        EXPECT_TRUE(std::isnan(DsmHeight(d, p.x(), p.y())));
      } else {
        EXPECT_EQ(DsmHeight(d, p.x(), p.y()), d.at(c, r)) << c << " " << r;
      }
    }
  }
  // The corner shared by cells (0,0), (1,0), (0,1), (1,1).
  EXPECT_EQ(DsmHeight(d, kUtm.x() + 0.5, kUtm.y() - 0.5), (10 + 11 + 14 + 15) / 4.0);
  // Half-way between two centres along a row, and a quarter of the way.
  EXPECT_EQ(DsmHeight(d, kUtm.x() + 1.0, kUtm.y() - 0.25), 11.5);
  EXPECT_EQ(DsmHeight(d, kUtm.x() + 0.375, kUtm.y() - 0.75), 14.25);
  // The raster's outer corner holds the edge value; beyond it, nothing.
  EXPECT_EQ(DsmHeight(d, kUtm.x(), kUtm.y()), 10);
  EXPECT_TRUE(std::isnan(DsmHeight(d, kUtm.x() - 0.01, kUtm.y())));
  EXPECT_TRUE(std::isnan(DsmHeight(d, kUtm.x() + 1, kUtm.y() - 1.51)));
  // Next to the empty cell: between centres it has weight, so no value.
  EXPECT_TRUE(std::isnan(DsmHeight(d, kUtm.x() + 1.5, kUtm.y() - 1.0)));
  EXPECT_EQ(DsmHeight(d, kUtm.x() + 1.25, kUtm.y() - 1.0), 18);
}

TEST(EvaluateDsm, BilinearReproducesALinearSurface) {
  GeoRaster d;
  d.width = 20;
  d.height = 15;
  d.origin_x = kUtm.x();
  d.origin_y = kUtm.y();
  d.cell_size = 2;
  auto linear = [](double x, double y) {
    return 100 + 0.25 * (x - kUtm.x()) - 0.5 * (kUtm.y() - y);
  };
  for (int r = 0; r < d.height; ++r) {
    for (int c = 0; c < d.width; ++c) {
      const Eigen::Vector2d p = d.CellCenter(c, r);
      d.values.push_back(static_cast<float>(linear(p.x(), p.y())));
    }
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(1, 39), uy(-29, -1);
  for (int i = 0; i < 200; ++i) {
    const double x = kUtm.x() + ux(rng), y = kUtm.y() + uy(rng);
    EXPECT_NEAR(DsmHeight(d, x, y), linear(x, y), 1e-9);
  }
}

TEST(EvaluateDsm, StatisticsAndPointsOutside) {
  const GeoRaster d = SmallDsm();
  Points cloud;
  for (int c = 0; c < 4; ++c) {
    const Eigen::Vector2d p = d.CellCenter(c, 1);
    cloud.emplace_back(p.x(), p.y(), d.at(c, 1) + (c % 2 ? 0.5 : -1.5));
  }
  cloud.emplace_back(kUtm.x() + 10, kUtm.y(), 0);  // outside
  const Eigen::Vector2d e = d.CellCenter(3, 2);
  cloud.emplace_back(e.x(), e.y(), 0);  // on the empty cell
  EvaluateOptions o = Options(0, {1});
  o.reference = "dsm.tif";
  const EvaluationReport r = EvaluateAgainstDsm(cloud, d, nullptr, o);
  EXPECT_EQ(r.reference_points, 11);
  EXPECT_EQ(r.without_reference, 2);
  EXPECT_EQ(r.rows[0].checkpoints, 4);
  EXPECT_NEAR(r.rows[0].rmse, std::sqrt((2 * 2.25 + 2 * 0.25) / 4), 1e-9);
  EXPECT_NEAR(r.rows[0].mean, -0.5, 1e-9);
  EXPECT_EQ(r.rows[1].checkpoints, 2);
  EXPECT_FALSE(r.completeness.has_value());
}

TEST(EvaluateDsm, CompletenessOnAConstructedDsm) {
  GeoRaster d;
  d.width = 10;
  d.height = 8;
  d.origin_x = kUtm.x();
  d.origin_y = kUtm.y();
  d.cell_size = 1;
  d.values.assign(80, 50.0f);
  d.at(3, 2) = d.at(6, 4) = std::numeric_limits<float>::quiet_NaN();  // inside the box
  // Box over the centres of columns 2..7 and rows 1..5: 30 cells, 2 empty.
  const DsmFootprint box =
      FootprintFromBox(d, kUtm.x() + 2.5, kUtm.y() - 5.5, kUtm.x() + 7.5, kUtm.y() - 1.5);
  Points cloud;
  auto at = [&](double col, double row, double dz) {
    cloud.emplace_back(kUtm.x() + col, kUtm.y() - row, 50 + dz);
  };
  // Seven filled footprint cells, one of them twice.
  for (int k = 0; k < 7; ++k) at(2.5 + k % 6, 1.5 + k / 6, 0.2);
  at(2.7, 1.4, -0.3);
  at(5.5, 5.5, 1.5);  // a footprint cell, beyond the tolerance
  at(0.5, 0.5, 0.0);  // within tolerance, outside the footprint
  at(9.5, 7.5, 0.0);  // within tolerance, outside the footprint
  at(3.5, 2.5, 0.0);  // the empty cell: no reference
  EvaluateOptions o = Options();
  o.reference = "dsm.tif";
  const EvaluationReport r = EvaluateAgainstDsm(cloud, d, &box, o);
  ASSERT_TRUE(r.completeness.has_value());
  EXPECT_EQ(r.completeness->cells, 28);
  EXPECT_EQ(r.completeness->filled, 7);
  EXPECT_DOUBLE_EQ(r.completeness->share, 7.0 / 28);
  EXPECT_EQ(r.without_reference, 1);
}

TEST(EvaluateDsm, BlockFootprintIsTheCellsSeenTwice) {
  // Nadir cameras 1000 above flat ground with f = 1000 px and 1000 px images:
  // each sees 1000 x 1000 around its centre. A at x = 0, B at x = 400, C far
  // north; DSM cells of 100 with centres at -950 .. 1350, -550 .. 550.
  const Intrinsics k = Intrinsics::FromPixels(1000, 1000, 499.5, 499.5, 1000, 1000);
  Block block;
  for (const Eigen::Vector2d& c :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(400, 0), Eigen::Vector2d(0, 3000)}) {
    BlockImage im;
    im.name = "im" + std::to_string(block.images.size());
    im.camera = Camera::FromAngles(k, {c.x(), c.y(), 1000}, 0, 0, 0, AngleOrder::kOmegaPhiKappa,
                                   AngleUnit::kDegree);
    block.images.push_back(im);
  }
  GeoRaster d;
  d.width = 24;
  d.height = 12;
  d.origin_x = -1000;
  d.origin_y = 600;
  d.cell_size = 100;
  d.values.assign(d.width * d.height, 0.0f);
  const DsmFootprint f = FootprintFromBlock(d, block);
  long expected = 0;
  for (int r = 0; r < d.height; ++r) {
    for (int c = 0; c < d.width; ++c) {
      const Eigen::Vector2d p = d.CellCenter(c, r);
      const bool in_a = std::abs(p.x()) < 500 && std::abs(p.y()) < 500;
      const bool in_b = std::abs(p.x() - 400) < 500 && std::abs(p.y()) < 500;
      EXPECT_EQ(f.mask[r * d.width + c] != 0, in_a && in_b) << p.transpose();
      expected += in_a && in_b;
    }
  }
  EXPECT_EQ(expected, 6 * 10);
}

class EvaluateFilesTest : public test::ScratchTest {
 protected:
  std::string Message(const EvaluateOptions& o) {
    try {
      Evaluate(o);
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      return m;
    }
    ADD_FAILURE() << "expected an Error";
    return "";
  }
  EvaluateOptions FileOptions(const std::string& cloud, const std::string& reference) {
    EvaluateOptions o = Options();
    o.cloud = dir_ / cloud;
    o.reference = dir_ / reference;
    return o;
  }
  void WriteLidar() {
    std::vector<PointRecord> points;
    for (const Eigen::Vector3d& p : GridLidar(Plane{kUtm, 0, 0}, 0.5, 21)) {
      PointRecord r;
      r.x = p.x();
      r.y = p.y();
      r.z = p.z();
      points.push_back(r);
    }
    WriteLas(dir_ / "lidar.las", points);
  }
};

TEST_F(EvaluateFilesTest, ReadsEachCloudFormat) {
  WriteLidar();
  std::ofstream(dir_ / "cloud.xyz") << "# x y z\n512003 5405004 300.25\n";
  PointCloud ply;
  ply.points.resize(1);
  ply.points[0].position = {kUtm.x() + 3, kUtm.y() + 4, 300.25};
  WritePly(dir_ / "cloud.ply", ply);
  std::vector<PointRecord> las(1);
  las[0].x = kUtm.x() + 3;
  las[0].y = kUtm.y() + 4;
  las[0].z = 300.25;
  WriteLas(dir_ / "cloud.las", las);
  for (const char* name : {"cloud.xyz", "cloud.ply", "cloud.las"}) {
    const EvaluationReport r = Evaluate(FileOptions(name, "lidar.las"));
    EXPECT_EQ(r.rows[0].checkpoints, 1) << name;
    EXPECT_NEAR(r.rows[0].mean, 0.25, 1e-9) << name;
    EXPECT_NEAR(r.spacing, 0.5, 1e-9) << name;
  }
}

TEST_F(EvaluateFilesTest, MalformedOrTruncatedLasIsAnInputError) {
  WriteLidar();
  std::ofstream(dir_ / "cloud.xyz") << "512003 5405004 300\n";
  const auto size = fs::file_size(dir_ / "lidar.las");
  fs::resize_file(dir_ / "lidar.las", size - 10);
  EXPECT_NE(Message(FileOptions("cloud.xyz", "lidar.las")).find("lidar.las: truncated"),
            std::string::npos);
  std::ofstream(dir_ / "junk.las") << "this is not a LAS file, just text";
  EXPECT_NE(Message(FileOptions("cloud.xyz", "junk.las")).find("junk.las: not a LAS file"),
            std::string::npos);
}

TEST_F(EvaluateFilesTest, EmptyCloudsAreRefused) {
  WriteLidar();
  std::ofstream(dir_ / "empty.xyz") << "# nothing here\n";
  EXPECT_NE(Message(FileOptions("empty.xyz", "lidar.las")).find("empty.xyz: the cloud holds no"),
            std::string::npos);
  WritePly(dir_ / "empty.ply", PointCloud{});
  EXPECT_NE(Message(FileOptions("empty.ply", "lidar.las")).find("empty.ply: the cloud holds no"),
            std::string::npos);
  EXPECT_THROW(EvaluateAgainstLidar({}, {{0, 0, 0}, {1, 0, 0}}, Options(1)), Error);
}

TEST_F(EvaluateFilesTest, NonFiniteCoordinatesAreRefused) {
  WriteLidar();
  std::ofstream(dir_ / "nan.xyz") << "1 2 3\nnan 2 3\n";
  const std::string m = Message(FileOptions("nan.xyz", "lidar.las"));
  EXPECT_NE(m.find("nan.xyz:2:"), std::string::npos) << m;
  std::ofstream(dir_ / "nan.ply") << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                     "property float y\nproperty float z\nend_header\n1 inf 3\n";
  EXPECT_NE(Message(FileOptions("nan.ply", "lidar.las")).find("nan.ply:8: non-finite"),
            std::string::npos);
  try {
    EvaluateAgainstLidar({{1, 2, 3}, {kNaN, 2, 3}}, {{0, 0, 0}, {1, 0, 0}}, Options(1));
    ADD_FAILURE() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cloud.ply: point 1 (0-based) has a non-finite"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(EvaluateFilesTest, MissingFilesAndUnknownExtensionsAreNamed) {
  WriteLidar();
  EXPECT_NE(Message(FileOptions("missing.ply", "lidar.las")).find("missing.ply: cannot open"),
            std::string::npos);
  std::ofstream(dir_ / "cloud.xyz") << "1 2 3\n";
  EXPECT_NE(Message(FileOptions("cloud.xyz", "missing.las")).find("missing.las: cannot open"),
            std::string::npos);
  EXPECT_NE(Message(FileOptions("cloud.xyz", "missing.tif")).find("missing.tif"),
            std::string::npos);
  EXPECT_NE(Message(FileOptions("cloud.xyz", "lidar.e57")).find("unknown reference extension"),
            std::string::npos);
  EXPECT_NE(Message(FileOptions("cloud.laz", "lidar.las")).find("LAZ-compressed"),
            std::string::npos);
}

TEST_F(EvaluateFilesTest, FootprintWithLidarAndBadOutputPathsFailFirst) {
  WriteLidar();
  std::ofstream(dir_ / "cloud.xyz") << "1 2 3\n";
  EvaluateOptions o = FileOptions("cloud.xyz", "lidar.las");
  o.footprint = {0, 0, 1, 1};
  EXPECT_NE(Message(o).find("apply to a DSM reference"), std::string::npos);
  o = FileOptions("cloud.xyz", "lidar.las");
  o.json = dir_ / "no" / "such" / "report.json";
  EXPECT_NE(Message(o).find("does not exist"), std::string::npos);
}

TEST(EvaluateOptionsTest, DefaultsAreValidAndEveryBoundaryIsChecked) {
  EXPECT_TRUE(Options().Check());
  EXPECT_EQ(EvaluateOptions().tolerance, 1.0);
  EXPECT_FALSE(EvaluateOptions().Check());  // no cloud, no reference
  auto problem = [](const std::function<void(EvaluateOptions*)>& change) {
    EvaluateOptions o = Options();
    change(&o);
    return o.Problem();
  };
  EXPECT_NE(problem([](auto* o) { o->radius = -1; }).find("--radius"), std::string::npos);
  EXPECT_NE(problem([](auto* o) { o->radius = kNaN; }).find("--radius"), std::string::npos);
  EXPECT_EQ(problem([](auto* o) { o->radius = 0.5; }), "");
  EXPECT_NE(problem([](auto* o) { o->tolerance = 0; }).find("--tolerance"), std::string::npos);
  EXPECT_NE(problem([](auto* o) { o->tolerance = INFINITY; }).find("--tolerance"),
            std::string::npos);
  EXPECT_NE(problem([](auto* o) {
              o->drop_above = {1, 0};
            }).find("--drop-above 0"),
            std::string::npos);
  EXPECT_NE(problem([](auto* o) { o->drop_above = {-2}; }).find("--drop-above"), std::string::npos);
  EXPECT_NE(problem([](auto* o) { o->footprint = {0, 0, 1}; }).find("3 values"), std::string::npos);
  EXPECT_NE(problem([](auto* o) {
              o->footprint = {2, 0, 1, 1};
            }).find("xmin < xmax"),
            std::string::npos);
  EXPECT_EQ(problem([](auto* o) { o->footprint = {0, 0, 1, 1}; }), "");
  EXPECT_NE(problem([](auto* o) {
              o->footprint = {0, 0, 1, 1};
              o->block = "block.yaml";
            }).find("both given"),
            std::string::npos);
}

// The tolerance is printed in the CRS's vertical unit (metres for a
// geographic CRS), and a cloud without CRS says its frame is local.
TEST(PrintEvaluationTable, TheToleranceSaysItsUnit) {
  for (const auto& [unit, want] :
       {std::pair<std::string, std::string>{"", "(local frame units)"},
        std::pair<std::string, std::string>{"m", "(m)"},
        std::pair<std::string, std::string>{"deg", "(m)"},
        std::pair<std::string, std::string>{"US survey foot", "(US survey foot)"}}) {
    EvaluationReport r;
    r.unit = unit;
    r.tolerance = 1;
    std::ostringstream out;
    PrintEvaluationTable(r, out);
    EXPECT_NE(out.str().find("tolerance     1 " + want), std::string::npos) << out.str();
    EXPECT_EQ(out.str().find("CRS units"), std::string::npos) << out.str();
  }
}

}  // namespace
}  // namespace sapmvs

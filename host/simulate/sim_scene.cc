#include "sapmvs/simulate/sim_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>

#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs::sim {

uint8_t LasClass(SurfaceClass k) {
  switch (k) {
    case SurfaceClass::kRoof:
      return 6;
    case SurfaceClass::kTree:
      return 5;
    case SurfaceClass::kWater:
      return 9;
    default:
      return 2;
  }
}

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStorey = 3.0;  // m

uint64_t SplitMix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double LatticeValue(int64_t ix, int64_t iy, uint64_t seed) {
  const uint64_t h = SplitMix(seed ^ SplitMix(static_cast<uint64_t>(ix) * 0x632be59bd9b4e019ULL ^
                                              SplitMix(static_cast<uint64_t>(iy))));
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

double ValueNoise(double x, double y, uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * tx * (tx * (tx * 6 - 15) + 10);
  ty = ty * ty * ty * (ty * (ty * 6 - 15) + 10);
  const double a = LatticeValue(ix, iy, seed), b = LatticeValue(ix + 1, iy, seed);
  const double c = LatticeValue(ix, iy + 1, seed), d = LatticeValue(ix + 1, iy + 1, seed);
  return (1 - ty) * ((1 - tx) * a + tx * b) + ty * ((1 - tx) * c + tx * d);
}

// A rectangle of half sizes (a, b) centred at c, rotated by `angle`.
struct Rect {
  Eigen::Vector2d c;
  double a, b, angle;
  Eigen::Vector2d Local(double x, double y) const {
    const double ca = std::cos(angle), sa = std::sin(angle);
    const double dx = x - c.x(), dy = y - c.y();
    return {ca * dx + sa * dy, -sa * dx + ca * dy};
  }
  bool Contains(double x, double y, double margin = 0) const {
    const Eigen::Vector2d l = Local(x, y);
    return std::abs(l.x()) <= a + margin && std::abs(l.y()) <= b + margin;
  }
  double Radius() const { return std::hypot(a, b); }
};

}  // namespace

double FractalNoise(double x, double y, double frequency, int octaves, uint64_t seed) {
  // A per-octave rotation and offset keep octaves from lining up.
  static const auto kRot = [] {
    std::array<std::pair<double, double>, 16> r{};
    for (size_t o = 0; o < r.size(); ++o) r[o] = {std::cos(0.7 + o * 1.3), std::sin(0.7 + o * 1.3)};
    return r;
  }();
  double sum = 0, amp = 1, norm = 0, f = frequency;
  for (int o = 0; o < octaves; ++o) {
    const auto [ca, sa] = kRot[static_cast<size_t>(o) % kRot.size()];
    const double rx = ca * x - sa * y, ry = sa * x + ca * y;
    sum += amp * ValueNoise(rx * f + 17.3 * o, ry * f - 9.1 * o, SplitMix(seed + o));
    norm += amp;
    amp *= 0.5;
    f *= 2.03;
  }
  return sum / norm;
}

bool SceneSpec::Check() const {
  bool ok = true;
  auto fail = [&ok](const char* what) {
    std::cerr << "SceneSpec: " << what << "\n";
    ok = false;
  };
  if (!(width > 0 && height > 0)) fail("width and height must be positive");
  if (!(cell > 0 && cell <= std::min(width, height) / 4)) fail("cell must be positive and small");
  if (!(width / cell * height / cell < 2.5e8)) fail("grid over 250 M cells");
  if (!(relief >= 0 && relief_wavelength > 0)) fail("relief >= 0, relief_wavelength > 0");
  if (!(building_min > 0 && building_max >= building_min)) fail("building size range");
  if (!(storey_min >= 1 && storey_max >= storey_min)) fail("storey range");
  for (double share : {building_density, pitched_share, tree_density, water_share}) {
    if (!(share >= 0 && share <= 1)) fail("shares must lie in [0, 1]");
  }
  return ok;
}

Scene Scene::Generate(const SceneSpec& spec, uint64_t seed) {
  if (!spec.Check()) throw Error("invalid scene specification");
  Scene s;
  s.seed_ = seed;
  s.cell_ = spec.cell;
  s.nx_ = static_cast<int>(std::ceil(spec.width / spec.cell));
  s.ny_ = static_cast<int>(std::ceil(spec.height / spec.cell));
  const size_t n = static_cast<size_t>(s.nx_) * s.ny_;
  s.z_.assign(n, 0.f);
  s.cls_.assign(n, static_cast<uint8_t>(SurfaceClass::kGrass));
  s.feature_.assign(n, 0);
  s.feature_colour_.assign(1, Eigen::Vector3f::Zero());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0, 1);
  const double w = s.width(), h = s.height(), c = s.cell_;
  auto cx = [&](int ix) { return (ix + 0.5) * c; };

  // Terrain, with bare soil where a large-scale noise is high.
  std::vector<float> terrain(n);
#pragma omp parallel for schedule(static)
  for (int iy = 0; iy < s.ny_; ++iy) {
    for (int ix = 0; ix < s.nx_; ++ix) {
      const double x = cx(ix), y = cx(iy);
      const double t =
          2 * spec.relief * (FractalNoise(x, y, 1 / spec.relief_wavelength, 5, seed + 1) - 0.5);
      terrain[s.Index(ix, iy)] = static_cast<float>(t);
      if (FractalNoise(x, y, 1 / 60.0, 3, seed + 2) > 0.68) {
        s.cls_[s.Index(ix, iy)] = static_cast<uint8_t>(SurfaceClass::kBareSoil);
      }
    }
  }
  s.z_ = terrain;

  // Visits the cells of a rectangle's bounding box.
  auto for_rect = [&](const Rect& r, double margin, auto fn) {
    const double rad = r.Radius() + margin;
    const int x0 = std::max(0, static_cast<int>((r.c.x() - rad) / c));
    const int x1 = std::min(s.nx_ - 1, static_cast<int>((r.c.x() + rad) / c));
    const int y0 = std::max(0, static_cast<int>((r.c.y() - rad) / c));
    const int y1 = std::min(s.ny_ - 1, static_cast<int>((r.c.y() + rad) / c));
    for (int iy = y0; iy <= y1; ++iy)
      for (int ix = x0; ix <= x1; ++ix)
        if (r.Contains(cx(ix), cx(iy), margin)) fn(ix, iy);
  };
  auto set_class = [&](int ix, int iy, SurfaceClass k) {
    s.cls_[s.Index(ix, iy)] = static_cast<uint8_t>(k);
  };
  auto is = [&](int ix, int iy, SurfaceClass k) {
    return s.cls_[s.Index(ix, iy)] == static_cast<uint8_t>(k);
  };

  // Water: a few ellipses, flat at their lowest terrain.
  double water_left = spec.water_share * w * h;
  for (int tries = 0; water_left > 0 && tries < 10; ++tries) {
    const double ra = std::sqrt(water_left / kPi) * (1.0 + 0.6 * uni(rng)),
                 rb = water_left / (kPi * ra);
    // Drawn y first, in named steps: the order of a constructor's arguments
    // is the compiler's, and the same seed must give the same scene from
    // gcc and clang (gcc drew y first).
    const double ctr_y = h * (0.15 + 0.7 * uni(rng));
    const Eigen::Vector2d ctr(w * (0.15 + 0.7 * uni(rng)), ctr_y);
    const double ang = kPi * uni(rng);
    float level = std::numeric_limits<float>::max();
    Rect box{ctr, ra, rb, ang};
    auto inside = [&](int ix, int iy) {
      const Eigen::Vector2d l = box.Local(cx(ix), cx(iy));
      return (l.x() * l.x()) / (ra * ra) + (l.y() * l.y()) / (rb * rb) <= 1;
    };
    for_rect(box, 0, [&](int ix, int iy) {
      if (inside(ix, iy)) level = std::min(level, terrain[s.Index(ix, iy)]);
    });
    for_rect(box, 0, [&](int ix, int iy) {
      if (!inside(ix, iy)) return;
      s.z_[s.Index(ix, iy)] = level - 0.3f;
      set_class(ix, iy, SurfaceClass::kWater);
    });
    water_left -= kPi * ra * rb;
  }

  // Roads along x and y at irregular spacing: not a periodic pattern.
  if (spec.road_spacing > 0) {
    for (int axis = 0; axis < 2; ++axis) {
      const double extent = axis == 0 ? h : w;
      for (double pos = spec.road_spacing * (0.3 + 0.5 * uni(rng)); pos < extent;
           pos += spec.road_spacing * (0.6 + 0.8 * uni(rng))) {
        const double half = 4 + 2 * uni(rng);
        const Rect r = axis == 0 ? Rect{{w / 2, pos}, w / 2, half, 0.02 * (uni(rng) - 0.5)}
                                 : Rect{{pos, h / 2}, half, h / 2, 0.02 * (uni(rng) - 0.5)};
        for_rect(r, 0, [&](int ix, int iy) {
          if (!is(ix, iy, SurfaceClass::kWater)) set_class(ix, iy, SurfaceClass::kRoad);
        });
      }
    }
  }

  // Flat paved squares.
  for (int i = 0; i < spec.squares; ++i) {
    const Rect r{{w * (0.1 + 0.8 * uni(rng)), h * (0.1 + 0.8 * uni(rng))},
                 15 + 20 * uni(rng),
                 15 + 20 * uni(rng),
                 0.3 * (uni(rng) - 0.5)};
    double sum = 0;
    int cnt = 0;
    for_rect(r, 0, [&](int ix, int iy) {
      sum += terrain[s.Index(ix, iy)];
      ++cnt;
    });
    if (cnt == 0) continue;
    for_rect(r, 0, [&](int ix, int iy) {
      if (is(ix, iy, SurfaceClass::kWater)) return;
      s.z_[s.Index(ix, iy)] = static_cast<float>(sum / cnt);
      set_class(ix, iy, SurfaceClass::kSquare);
    });
  }

  // Buildings on free land, flat or pitched, plus high-rise towers.
  // True when the rectangle (plus margin) lies inside the grid on grass or
  // bare soil only. Stops at the first occupied cell: most random placements
  // fail, and they should fail fast.
  auto free_land = [&](const Rect& r, double margin) {
    const double rad = r.Radius() + margin;
    if (r.c.x() - rad < 0 || r.c.y() - rad < 0 || r.c.x() + rad > w || r.c.y() + rad > h)
      return false;
    auto free_cell = [&](int ix, int iy) {
      return is(ix, iy, SurfaceClass::kGrass) || is(ix, iy, SurfaceClass::kBareSoil);
    };
    if (!free_cell(static_cast<int>(r.c.x() / c), static_cast<int>(r.c.y() / c))) return false;
    const int x0 = static_cast<int>((r.c.x() - rad) / c),
              x1 = std::min(s.nx_ - 1, static_cast<int>((r.c.x() + rad) / c));
    const int y0 = static_cast<int>((r.c.y() - rad) / c),
              y1 = std::min(s.ny_ - 1, static_cast<int>((r.c.y() + rad) / c));
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) {
        if (r.Contains(cx(ix), cx(iy), margin) && !free_cell(ix, iy)) return false;
      }
    }
    return true;
  };
  auto add_building = [&](const Rect& r, double wall_height, bool pitched) {
    float base = std::numeric_limits<float>::max();
    for_rect(r, 0, [&](int ix, int iy) { base = std::min(base, s.z_[s.Index(ix, iy)]); });
    const uint16_t id = static_cast<uint16_t>(s.feature_colour_.size());
    const double tone = uni(rng);
    Eigen::Vector3f colour = tone < 0.4   ? Eigen::Vector3f(0.55f, 0.22f, 0.15f)   // red tiles
                             : tone < 0.7 ? Eigen::Vector3f(0.42f, 0.42f, 0.45f)   // grey
                                          : Eigen::Vector3f(0.62f, 0.58f, 0.50f);  // light
    colour *= static_cast<float>(0.8 + 0.4 * uni(rng));
    s.feature_colour_.push_back(colour);
    // The ridge of a pitched roof runs along the longer side.
    const bool along_a = r.a >= r.b;
    const double short_half = along_a ? r.b : r.a;
    const double ridge = 0.7 * short_half;
    for_rect(r, 0, [&](int ix, int iy) {
      double roof = base + wall_height;
      if (pitched) {
        const Eigen::Vector2d l = r.Local(cx(ix), cx(iy));
        const double across = std::abs(along_a ? l.y() : l.x());
        roof += ridge * (1 - across / short_half);
      }
      s.z_[s.Index(ix, iy)] = static_cast<float>(roof);
      set_class(ix, iy, SurfaceClass::kRoof);
      s.feature_[s.Index(ix, iy)] = id;
    });
  };
  for (int i = 0; i < spec.high_rises; ++i) {
    for (int tries = 0; tries < 200; ++tries) {
      const Rect r{
          {w * uni(rng), h * uni(rng)}, 10 + 8 * uni(rng), 10 + 8 * uni(rng), kPi / 2 * uni(rng)};
      if (!free_land(r, 6)) continue;
      add_building(r, 40 + 40 * uni(rng), false);
      break;
    }
  }
  double built = 0;
  const double target = spec.building_density * w * h;
  for (int tries = 0; built < target && tries < 20000; ++tries) {
    const double a = 0.5 * (spec.building_min + (spec.building_max - spec.building_min) * uni(rng));
    const double b = a * (0.35 + 0.65 * uni(rng));
    const Rect r{{w * uni(rng), h * uni(rng)},
                 a,
                 b,
                 tries % 3 == 0 ? kPi * uni(rng) : 0.1 * (uni(rng) - 0.5)};
    if (!free_land(r, 4)) continue;
    const double storeys =
        std::round(spec.storey_min + (spec.storey_max - spec.storey_min) * uni(rng));
    add_building(r, storeys * kStorey, uni(rng) < spec.pitched_share);
    built += 4 * a * b;
  }

  // Tree crowns: domes on free land.
  double crowns = 0;
  const double crown_target = spec.tree_density * w * h;
  for (int tries = 0; crowns < crown_target && tries < 200000; ++tries) {
    const double rad = 2 + 3 * uni(rng);
    const double ctr_y = h * uni(rng);  // y before x, as for the water above
    const Eigen::Vector2d ctr(w * uni(rng), ctr_y);
    const Rect box{ctr, rad, rad, 0};
    if (!free_land(box, -rad * 0.3)) continue;
    const double top = 5 + 10 * uni(rng);
    const uint16_t id = static_cast<uint16_t>(s.feature_colour_.size());
    s.feature_colour_.push_back(Eigen::Vector3f(0.10f, 0.22f, 0.07f) *
                                static_cast<float>(0.7 + 0.6 * uni(rng)));
    for_rect(box, 0, [&](int ix, int iy) {
      const double r2 = (Eigen::Vector2d(cx(ix), cx(iy)) - ctr).squaredNorm() / (rad * rad);
      if (r2 > 1) return;
      const float zt = static_cast<float>(terrain[s.Index(ix, iy)] + top * std::sqrt(1 - r2));
      if (zt > s.z_[s.Index(ix, iy)] && !is(ix, iy, SurfaceClass::kRoof)) {
        s.z_[s.Index(ix, iy)] = zt;
        set_class(ix, iy, SurfaceClass::kTree);
        s.feature_[s.Index(ix, iy)] = id;
      }
    });
    crowns += kPi * rad * rad;
  }

  s.BuildBlockMax();
  const double el = 50 * kPi / 180, az = 135 * kPi / 180;  // sun from the south-east
  s.sun_ = Eigen::Vector3d(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  s.sun_ = Eigen::Vector3d(s.sun_.x(), -std::abs(s.sun_.y()), s.sun_.z()).normalized();
  return s;
}

void Scene::BuildBlockMax() {
  bx_ = (nx_ + kBlock - 1) / kBlock;
  by_ = (ny_ + kBlock - 1) / kBlock;
  block_max_.assign(static_cast<size_t>(bx_) * by_, -std::numeric_limits<float>::max());
  zmin_ = std::numeric_limits<double>::max();
  zmax_ = -zmin_;
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const float z = z_[Index(ix, iy)];
      float& m = block_max_[static_cast<size_t>(iy / kBlock) * bx_ + ix / kBlock];
      m = std::max(m, z);
      zmin_ = std::min(zmin_, static_cast<double>(z));
      zmax_ = std::max(zmax_, static_cast<double>(z));
    }
  }
}

double Scene::HeightAt(double x, double y) const {
  const int ix = static_cast<int>(std::floor(x / cell_)),
            iy = static_cast<int>(std::floor(y / cell_));
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return kNaN;
  return z_[Index(ix, iy)];
}

Eigen::Vector3d Scene::TopNormal(int ix, int iy) const {
  // Central differences that do not reach across walls (steps over two
  // cells' height), so roofs and ground next to walls keep their own slope.
  const double z = z_[Index(ix, iy)];
  auto side = [&](int jx, int jy) {
    if (jx < 0 || jy < 0 || jx >= nx_ || jy >= ny_) return z;
    const double zn = z_[Index(jx, jy)];
    return std::abs(zn - z) > 2 * cell_ ? z : zn;
  };
  const double gx = (side(ix + 1, iy) - side(ix - 1, iy)) / (2 * cell_);
  const double gy = (side(ix, iy + 1) - side(ix, iy - 1)) / (2 * cell_);
  return Eigen::Vector3d(-gx, -gy, 1).normalized();
}

Hit Scene::TopAt(double x, double y) const {
  Hit hit;
  const int ix = static_cast<int>(std::floor(x / cell_)),
            iy = static_cast<int>(std::floor(y / cell_));
  if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return hit;
  hit.valid = true;
  hit.point = {x, y, z_[Index(ix, iy)]};
  hit.normal = TopNormal(ix, iy);
  hit.cls = static_cast<SurfaceClass>(cls_[Index(ix, iy)]);
  hit.feature = feature_[Index(ix, iy)];
  return hit;
}

Eigen::Vector3d Scene::Albedo(const Hit& hit) const {
  const double x = hit.point.x(), y = hit.point.y(), z = hit.point.z();
  const uint64_t s = seed_ * 31 + 7;
  // Fine texture from about 1 m to 40 m, non-periodic.
  auto tex = [&](double u, double v, uint64_t k, double f0) {
    return FractalNoise(u, v, f0, 5, s + k);
  };
  const Eigen::Vector3d feat = hit.feature < feature_colour_.size()
                                   ? feature_colour_[hit.feature].cast<double>()
                                   : Eigen::Vector3d(0.5, 0.5, 0.5);
  if (hit.wall) {
    // Facades: texture over (along the wall, height).
    const double along = std::abs(hit.normal.x()) > 0.5 ? y : x;
    const double n = tex(along, z * 1.3, 11, 1 / 6.0);
    return Eigen::Vector3d(0.72, 0.68, 0.60) * (0.55 + 0.8 * n) + 0.15 * feat;
  }
  // Each noise only where a class uses it: they are most of a ray's cost.
  auto large = [&] { return tex(x, y, 1, 1 / 40.0); };
  auto fine = [&] { return tex(x, y, 2, 1 / 3.0); };
  switch (hit.cls) {
    case SurfaceClass::kGrass:
      return Eigen::Vector3d(0.22, 0.38, 0.12) * (0.3 + 0.5 * large() + 0.9 * fine());
    case SurfaceClass::kBareSoil:
      return Eigen::Vector3d(0.50, 0.40, 0.28) * (0.35 + 0.4 * large() + 0.8 * fine());
    case SurfaceClass::kRoad:
      return Eigen::Vector3d(0.33, 0.33, 0.35) * (0.45 + 0.3 * large() + 0.8 * fine());
    case SurfaceClass::kSquare:
      return Eigen::Vector3d(0.62, 0.56, 0.48) * (0.4 + 0.3 * large() + 0.8 * fine());
    case SurfaceClass::kRoof:
      return feat * (0.35 + 0.3 * large() + 1.0 * tex(x, y, 3, 1 / 2.0));
    case SurfaceClass::kTree:
      return feat * (0.35 + 1.3 * tex(x, y, 4, 1 / 1.5));
    case SurfaceClass::kWater:
      // Nearly textureless, as real water is for a matcher.
      return Eigen::Vector3d(0.05, 0.09, 0.13) * (0.98 + 0.04 * large());
  }
  return {0.5, 0.5, 0.5};
}

Eigen::Vector3d Scene::Shade(const Hit& hit) const {
  const double lambert = std::max(0.0, hit.normal.dot(sun_));
  return Albedo(hit) * (0.35 + 0.75 * lambert);
}

}  // namespace sapmvs::sim

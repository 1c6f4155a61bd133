// Ray casting against the scene's cell columns: an Amanatides-Woo walk over
// the cells, skipping whole blocks of cells that the ray passes above.

#include <cmath>
#include <limits>

#include "sapmvs/simulate/sim_scene.h"

namespace sapmvs::sim {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

Hit Scene::Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  Hit hit;
  if (!(d.z() < 0)) return hit;  // cameras look down at the scene
  const double w = width(), h = height();
  // Parameter range: from where the ray comes down to the highest top to
  // where it passes below the lowest, clipped to the grid's footprint.
  double t0 = std::max(0.0, (zmax_ - o.z()) / d.z());
  double t1 = (zmin_ - 1e-3 - o.z()) / d.z();
  for (int a = 0; a < 2; ++a) {
    const double lo = 0, hi = a == 0 ? w : h;
    if (d[a] == 0) {
      if (o[a] < lo || o[a] > hi) return hit;
      continue;
    }
    double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return hit;

  const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
  const double block = kBlock * cell_;
  double t = t0;
  int last_axis = -1;                            // axis of the last cell boundary crossed
  float prev_z = static_cast<float>(zmax_ + 1);  // height of the cell the ray came from
  // The cell is located from the ray's position only after a block skip; the
  // cell walk carries its indices across block borders itself, since a
  // position exactly on a border may round into either cell.
  int ix = 0, iy = 0;
  bool locate = true;
  while (t < t1) {
    if (locate) {
      const Eigen::Vector3d p = o + t * d;
      // Rounding can leave the ray a hair outside the grid at its far side.
      if (p.x() < -1e-6 * cell_ || p.y() < -1e-6 * cell_ || p.x() > w + 1e-6 * cell_ ||
          p.y() > h + 1e-6 * cell_) {
        return hit;
      }
      ix = std::clamp(static_cast<int>(std::floor(p.x() / cell_)), 0, nx_ - 1);
      iy = std::clamp(static_cast<int>(std::floor(p.y() / cell_)), 0, ny_ - 1);
      locate = false;
    }
    const int bxi = ix / kBlock, byi = iy / kBlock;
    // Leave the block at once when the ray stays above everything in it.
    const double ex = d.x() == 0 ? kInf : ((bxi + (sx > 0)) * block - o.x()) / d.x();
    const double ey = d.y() == 0 ? kInf : ((byi + (sy > 0)) * block - o.y()) / d.y();
    const double t_block = std::min(std::min(ex, ey), t1);
    if (o.z() + t_block * d.z() > block_max_[static_cast<size_t>(byi) * bx_ + bxi]) {
      last_axis = ex < ey ? 0 : 1;
      prev_z = static_cast<float>(zmax_ + 1);
      // Always move on, also when rounding puts the exit at or behind t.
      t = std::max(t_block, t) + 1e-6 * cell_;
      locate = true;
      continue;
    }
    double tx = d.x() == 0 ? kInf : ((ix + (sx > 0)) * cell_ - o.x()) / d.x();
    double ty = d.y() == 0 ? kInf : ((iy + (sy > 0)) * cell_ - o.y()) / d.y();
    const double dtx = d.x() == 0 ? kInf : cell_ / std::abs(d.x());
    const double dty = d.y() == 0 ? kInf : cell_ / std::abs(d.y());
    while (t < t1) {
      const size_t idx = Index(ix, iy);
      const float top = z_[idx];
      const double t_out = std::min(std::min(tx, ty), t1);
      double t_hit = -1;
      bool riser = false;
      if (o.z() + t * d.z() <= top) {
        t_hit = t;  // entered through the side of the column
        riser = true;
      } else if (o.z() + t_out * d.z() <= top) {
        t_hit = (top - o.z()) / d.z();
      }
      if (t_hit >= 0) {
        hit.valid = true;
        hit.point = o + t_hit * d;
        hit.cls = static_cast<SurfaceClass>(cls_[idx]);
        hit.feature = feature_[idx];
        // Only the tall sides of buildings are walls; the small steps of
        // sloping ground, pitched roofs and tree crowns are shaded with the
        // smooth surface normal.
        hit.wall =
            riser && last_axis >= 0 && hit.cls == SurfaceClass::kRoof && top - prev_z > 2 * cell_;
        if (hit.wall) {
          hit.normal = last_axis == 0 ? Eigen::Vector3d(-sx, 0, 0) : Eigen::Vector3d(0, -sy, 0);
        } else {
          hit.normal = TopNormal(ix, iy);
          hit.point.z() = top;
        }
        return hit;
      }
      prev_z = top;
      if (tx < ty) {
        t = tx;
        tx += dtx;
        ix += sx;
        last_axis = 0;
      } else {
        t = ty;
        ty += dty;
        iy += sy;
        last_axis = 1;
      }
      if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) return hit;
      if (ix / kBlock != bxi || iy / kBlock != byi) break;
    }
  }
  return hit;
}

}  // namespace sapmvs::sim

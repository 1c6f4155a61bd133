#include "simulate/sim_ortho.h"

#include <cmath>

#include "sapmvs/simulate/simulate.h"

namespace sapmvs::sim {

TrueOrtho RenderTrueOrtho(const Scene& scene, double cell, int supersampling) {
  TrueOrtho ortho;
  GeoRaster& g = ortho.grid;
  // 1e-9: a scene that is a whole number of cells wide gets no extra column
  // from rounding.
  g.width = static_cast<int>(std::ceil(scene.width() / cell - 1e-9));
  g.height = static_cast<int>(std::ceil(scene.height() / cell - 1e-9));
  g.cell_size = cell;
  g.origin_x = 0;
  g.origin_y = scene.height();
  ortho.rgba.assign(static_cast<size_t>(g.width) * g.height * 4, 0);
  const int ss = supersampling;
  const double w = scene.width(), h = scene.height();
#pragma omp parallel for schedule(dynamic, 4)
  for (int row = 0; row < g.height; ++row) {
    for (int col = 0; col < g.width; ++col) {
      const double cx = (col + 0.5) * cell, cy = h - (row + 0.5) * cell;
      if (cx >= w || cy < 0) continue;  // alpha stays 0
      Eigen::Vector3d acc = Eigen::Vector3d::Zero();
      int n = 0;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const double x = (col + (sx + 0.5) / ss) * cell, y = h - (row + (sy + 0.5) / ss) * cell;
          const Hit hit = scene.TopAt(x, y);
          if (!hit.valid) continue;
          acc += scene.Shade(hit);
          ++n;
        }
      }
      if (n == 0) continue;
      uint8_t* px = &ortho.rgba[(static_cast<size_t>(row) * g.width + col) * 4];
      for (int c = 0; c < 3; ++c)
        px[c] = static_cast<uint8_t>(std::lround(EncodeChannel(acc[c] / n, 1.0)));
      px[3] = 255;
    }
  }
  return ortho;
}

}  // namespace sapmvs::sim

#pragma once
// An image's view of the DSM: at each pixel, the depth of the nearest DSM
// surface (a z-buffer), so that a ground point hidden behind a roof or a
// tree in that image is known to be hidden. The DSM is drawn as two
// triangles between the centres of every 2 x 2 valid cells, a surface
// without holes between the cells; where those four heights span a step,
// as blocks: each cell flat to its sides, walls between.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ortho/ortho_surface.h"
#include "sapmvs/block/camera.h"
#include "sapmvs/io/raster_io.h"

namespace sapmvs {

class OrthoDepthBuffer {
 public:
  // Draws the cells of `dsm` in `window` as `camera` (a pinhole camera, the
  // image's at the level) sees them, as blocks where `walls` (WallQuads of
  // `dsm`) marks the quad. A point counts as seen when it lies at most
  // `tolerance` (CRS units) behind the drawn surface: a point on the
  // surface, tested at the nearest pixel, must not hide itself.
  OrthoDepthBuffer(const Camera& camera, const GeoRaster& dsm, const CellWindow& window,
                   const std::vector<uint8_t>& walls, double tolerance);

  // Whether world point `x` is in the image and not hidden; its pixel in
  // `uv` then.
  bool Sees(const Eigen::Vector3d& x, Eigen::Vector2d* uv) const;

 private:
  void DrawTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

  const Camera& camera_;
  int width_ = 0, height_ = 0;
  double tolerance_ = 0;
  std::vector<float> depth_;  // +inf where nothing was drawn
};

}  // namespace sapmvs

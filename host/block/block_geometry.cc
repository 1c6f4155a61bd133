#include "sapmvs/block/block_geometry.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

#include "sapmvs/block/dem.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"

namespace sapmvs {
namespace {

// Fewer tie points than this over a whole block are chance matches, not a
// surface.
constexpr size_t kMinTiePoints = 20;
double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

Eigen::Vector2d CenterPixel(const Camera& cam) {
  return {0.5 * (cam.width() - 1), 0.5 * (cam.height() - 1)};
}

// Intersection of the ray through `uv` with the plane Z = z; NaN when it
// does not go towards the plane.
Eigen::Vector3d OnPlaneZ(const Camera& cam, const Eigen::Vector2d& uv, double z) {
  const Eigen::Vector3d d = cam.Ray(uv);
  const double t = (z - cam.center().z()) / d.z();
  if (!(t > 0) || !std::isfinite(t)) return Eigen::Vector3d::Constant(kNaN);
  return cam.center() + t * d;
}

// Median depth of the points that project into the image.
std::optional<double> MedianDepth(const Camera& cam, const std::vector<Eigen::Vector3d>& pts) {
  std::vector<double> depths;
  for (const Eigen::Vector3d& p : pts) {
    const double d = cam.Depth(p);
    if (d > 0 && cam.InImage(cam.Project(p))) depths.push_back(d);
  }
  if (depths.empty()) return std::nullopt;
  return Median(depths);
}

}  // namespace

std::string NoSurfaceReason(const Block& block, const BlockGeometry& g) {
  if (g.num_valid > 0) return "";
  const std::string where = block.source.string() + ": ";
  if (g.source == SurfaceSource::kNone) {
    return where +
           "no surface estimate (no DEM, sparse points or ground height, and too few tie "
           "points); expected one: give --ground-height, or add ground_height or dem to the block";
  }
  std::string names;
  int up = 0;
  const size_t shown = std::min<size_t>(block.images.size(), 3);
  for (size_t i = 0; i < shown; ++i) names += (i ? ", '" : "'") + block.images[i].name + "'";
  if (block.images.size() > shown)
    names += " and " + std::to_string(block.images.size() - shown) + " more";
  for (const BlockImage& im : block.images) up += im.camera.ViewingDirection().z() > 0;
  std::string what = "the " + ToString(g.source);
  if (g.source == SurfaceSource::kGroundHeight && block.ground_height) {
    char z[64];
    std::snprintf(z, sizeof(z), " (Z = %.3f)", *block.ground_height);
    what += z;
  }
  return where + "no image sees " + what + ": the optical axes of " + names + " do not meet it" +
         (up > 0 ? " (" + std::to_string(up) + " of " + std::to_string(block.images.size()) +
                       " cameras look up)"
                 : "") +
         "; expected cameras looking at the scene (check the orientation's angles and "
         "convention)";
}

std::string ToString(SurfaceSource source) {
  switch (source) {
    case SurfaceSource::kDem:
      return "DEM";
    case SurfaceSource::kSparsePoints:
      return "sparse points";
    case SurfaceSource::kGroundHeight:
      return "ground height";
    case SurfaceSource::kTiePoints:
      return "tie points";
    case SurfaceSource::kNone:
      return "none";
  }
  return "?";
}

BlockGeometry EstimateBlockGeometry(const Block& block) {
  BlockGeometry g;
  g.images.resize(block.images.size());
  std::optional<Dem> dem;
  if (!block.dem.empty()) dem = Dem::Load(block.dem);
  std::vector<Eigen::Vector3d> tie_positions;
  if (!dem && block.sparse_points.empty() && !block.ground_height) {
    g.tie_points = TriangulateTiePoints(block);
    for (const TiePoint& t : g.tie_points) tie_positions.push_back(t.position);
  }
  if (dem)
    g.source = SurfaceSource::kDem;
  else if (!block.sparse_points.empty())
    g.source = SurfaceSource::kSparsePoints;
  else if (block.ground_height)
    g.source = SurfaceSource::kGroundHeight;
  else if (tie_positions.size() >= kMinTiePoints)
    g.source = SurfaceSource::kTiePoints;

  int down = 0;
  std::vector<double> gsds, heights;
  for (size_t i = 0; i < block.images.size(); ++i) {
    const Camera& cam = block.images[i].camera;
    ImageGeometry& ig = g.images[i];
    ig.looks_down = cam.ViewingDirection().z() < -0.5;
    down += ig.looks_down;
    const Eigen::Vector2d center = CenterPixel(cam);
    Eigen::Vector3d p = Eigen::Vector3d::Constant(kNaN);
    switch (g.source) {
      case SurfaceSource::kDem:
        p = dem->Intersect(cam.center(), cam.ViewingDirection());
        if (!p.allFinite()) p = OnPlaneZ(cam, center, dem->MedianHeight());
        break;
      case SurfaceSource::kSparsePoints:
      case SurfaceSource::kTiePoints:
        if (auto d = MedianDepth(cam, g.source == SurfaceSource::kSparsePoints ? block.sparse_points
                                                                               : tie_positions)) {
          p = cam.BackProject(center, *d);
        }
        break;
      case SurfaceSource::kGroundHeight:
        p = OnPlaneZ(cam, center, *block.ground_height);
        break;
      case SurfaceSource::kNone:
        break;
    }
    if (!p.allFinite()) continue;
    ig.valid = true;
    ig.scene_point = p;
    ig.depth = cam.Depth(p);
    ig.height_above = cam.center().z() - p.z();
    ig.gsd = ig.looks_down ? cam.Footprint(p, Eigen::Vector3d::UnitZ()) : cam.FootprintFacing(p);
    const double w = cam.width() - 0.5, h = cam.height() - 0.5;
    const Eigen::Vector2d corners[4] = {{-0.5, -0.5}, {w, -0.5}, {w, h}, {-0.5, h}};
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d q =
          ig.looks_down ? OnPlaneZ(cam, corners[k], p.z()) : Eigen::Vector3d::Constant(kNaN);
      if (!q.allFinite()) q = cam.BackProject(corners[k], ig.depth);
      ig.footprint[k] = q;
    }
    gsds.push_back(ig.gsd);
    heights.push_back(ig.height_above);
    if (g.num_valid == 0) g.extent_min = g.extent_max = ig.footprint[0];
    for (const Eigen::Vector3d& q : ig.footprint) {
      g.extent_min = g.extent_min.cwiseMin(q);
      g.extent_max = g.extent_max.cwiseMax(q);
    }
    ++g.num_valid;
  }
  g.aerial = 2 * down > static_cast<int>(block.images.size());
  if (!gsds.empty()) {
    g.gsd_min = *std::min_element(gsds.begin(), gsds.end());
    g.gsd_max = *std::max_element(gsds.begin(), gsds.end());
    g.gsd_median = Median(gsds);
    double sum = 0;
    for (double h : heights) sum += h;
    g.flying_height = sum / static_cast<double>(heights.size());
  }
  return g;
}

}  // namespace sapmvs

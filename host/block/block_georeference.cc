#include "block/block_georeference.h"

#include <cmath>
#include <cstdio>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Distances from the Earth's centre a camera can have: from the polar
// radius (6,356.8 km) less 1 km to the equatorial one (6,378.1 km) plus
// 30 km.
constexpr double kMinEcefRadius = 6.3558e6;
constexpr double kMaxEcefRadius = 6.4082e6;

// The block moved from ECEF into the ENU frame about `reference`: a rigid
// motion, exact for cameras and points.
void EcefToEnu(const TopocentricToUtm& map, Block* block) {
  const Eigen::Matrix3d& r = map.enu_to_ecef();
  const Eigen::Vector3d& o = map.origin_ecef();
  for (BlockImage& im : block->images) {
    Camera& cam = im.camera;
    // x_cam = R_wc (X_ecef - C) = R_wc r (X_enu - C_enu).
    cam = Camera(cam.intrinsics(), cam.rotation() * r, r.transpose() * (cam.center() - o));
  }
  for (Eigen::Vector3d& p : block->sparse_points) p = r.transpose() * (p - o);
}

std::string MovedNote(const char* from, const GeoReference& g, const TopocentricToUtmReport& m) {
  char note[512];
  std::snprintf(note, sizeof(note),
                "UTM (EPSG:%d) from %s about lat %.8f, lon %.8f, h %.3f; camera rotations turned "
                "by the grid convergence %.4f deg, scale %.6f",
                m.epsg, from, g.latitude, g.longitude, g.altitude, m.convergence_deg, m.scale);
  std::string out = note;
  if (m.max_reprojection_change_px >= 0) {
    std::snprintf(note, sizeof(note), "; sparse points reproject within %.3g px (%d checked)",
                  m.max_reprojection_change_px, m.points_checked);
    out += note;
  }
  return out;
}

}  // namespace

bool LooksEcef(const Block& block) {
  if (block.images.empty()) return false;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), view = Eigen::Vector3d::Zero();
  for (const BlockImage& im : block.images) {
    const double r = im.camera.center().norm();
    if (!(r >= kMinEcefRadius && r <= kMaxEcefRadius)) return false;
    centre += im.camera.center();
    view += im.camera.ViewingDirection();
  }
  // Within 60 degrees of the Earth's centre, on average.
  return view.normalized().dot(-centre.normalized()) > 0.5;
}

GeoReference AsGeoReference(const Eigen::Vector3d& lat_lon_height) {
  GeoReference g;
  g.latitude = lat_lon_height.x();
  g.longitude = lat_lon_height.y();
  g.altitude = lat_lon_height.z();
  return g;
}

void ApplyFrame(const BlockReadOptions& options, Block* block) {
  const std::string where = block->source.string() + ": ";
  if (!options.crs.empty()) {
    if (options.enu_origin) {
      throw Error(where +
                  "--crs and --enu-origin both given; expected one (--crs for a block "
                  "already in that CRS, --enu-origin for one in a local east-north-up "
                  "frame)");
    }
    if (!block->crs.empty() && block->crs != options.crs) {
      throw Error(where + "the block names its CRS (" + block->crs + "); --crs " + options.crs +
                  " names another");
    }
    block->crs = options.crs;
    block->frame_note = "CRS as --crs names it";
    return;
  }
  if (!block->crs.empty()) {
    if (options.enu_origin) {
      throw Error(where + "the block is in " + block->crs +
                  "; --enu-origin is for a block in a local east-north-up frame");
    }
    return;
  }
  if (options.enu_origin) {
    // Checked with the options (BlockReadOptions::Problem); TopocentricToUtm
    // refuses a bad point too.
    const GeoReference g = AsGeoReference(*options.enu_origin);
    const TopocentricToUtmReport moved = MoveTopocentricToUtm(g, block);
    block->frame_note = MovedNote("ENU", g, moved);
    return;
  }
  if (LooksEcef(*block)) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const BlockImage& im : block->images) centre += im.camera.center();
    centre /= static_cast<double>(block->images.size());
    GeoReference g = GeodeticOf(centre);
    if (const std::string p = g.Problem(); !p.empty()) {
      throw Error(where + "camera centres read as ECEF lie outside the UTM zones; expected " + p);
    }
    EcefToEnu(TopocentricToUtm(g), block);
    const TopocentricToUtmReport moved = MoveTopocentricToUtm(g, block);
    block->frame_note = MovedNote("ECEF (camera centres at the Earth's radius)", g, moved);
    return;
  }
  // No CRS: say so, and how to give one.
  const std::string hint = "no CRS: give --crs, or --enu-origin for an ENU frame";
  block->frame_note = block->frame_note.empty() ? "local frame (" + hint + ")"
                                                : block->frame_note + " (" + hint + ")";
}

}  // namespace sapmvs

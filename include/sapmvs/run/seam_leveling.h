#pragma once
// Levelling the seams between group clouds before they are merged. Each
// group matches its own ground (ground_region.h), but with real
// orientations two groups' images place the same surface a few centimetres
// apart, and where their cores meet the merged surface steps by that much.
// Where both groups matched (the margins either side of the border between
// their cores) their heights are compared cell by cell, and the median
// difference along each stretch of the border is split between them: each
// group's points move half of it towards the other at the border, less and
// less away from it, none at `feather` and beyond. What is left of each
// cell's own offset (the median of the 3 x 3 cells around it) is split the
// same way and faded out across the band where both groups matched: on the
// Caliterra flight it took the median step between neighbouring DSM cells
// across a border from 2.40 to 2.17 cm (2.21 cm inside groups), the 90th
// percentile from 10.9 to 9.4 cm (9.4 cm). Heights only: the surfaces
// that steps show in a DSM are the ground and the roofs.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "sapmvs/run/core_index.h"

namespace sapmvs {

struct SeamOptions {
  // Side of the cells the two groups' heights are compared in, CRS units
  // (> 0): about two point spacings, so that each group has a few points in
  // a cell of its surface.
  double cell = 0;
  // Points within this distance of a border are compared (> 0): the margin
  // each group matched beyond its core.
  double band = 0;
  // Length of the stretches of a border each offset is measured over, and
  // the distance over which a group's correction fades out (> 0).
  double feather = 0;
  // Offsets larger than this (> 0) are not the groups' orientations but
  // their surfaces: one group sees a roof's edge or a crown where the other
  // sees the ground beside it. Such a stretch is left as it is.
  double max_offset = 0;
  std::string Problem() const;
};

class SeamLeveling {
 public:
  // `centers`: every group's ground centre (world XY), as the merge's cores.
  SeamLeveling(std::vector<Eigen::Vector2d> centers, const SeamOptions& options);

  // Takes a point of group g (world frame); points outside the bands are
  // ignored. Call for the points of every group, then Finish().
  void Add(int g, const Eigen::Vector3d& p);
  void Finish();

  // The height to add to point p of group g (0 far from any border, or when
  // no border of g was measured).
  double Correction(int g, const Eigen::Vector3d& p) const;

  // Borders measured (pairs of groups whose surfaces were compared), and
  // the median |offset| of the stretches levelled.
  int pairs() const { return static_cast<int>(pair_offset_.size()); }
  double median_offset() const { return median_offset_; }

 private:
  std::vector<Eigen::Vector2d> centers_;
  SeamOptions options_;
  CoreIndex cores_;  // the points' nearest centres, within the band
  // Per group, the groups whose border with it was measured, ascending:
  // those Correction sums over.
  std::vector<std::vector<int>> measured_with_;
  // Heights of pair (a < b)'s cells, per side: (a, b, cell x, cell y, side).
  std::map<std::tuple<int, int, int64_t, int64_t, int>, std::vector<float>> heights_;
  // Offsets z_a - z_b per stretch of a border (a, b, stretch x, stretch y),
  // NaN where it exceeds max_offset; and per pair over the whole border, for
  // stretches with too few cells of their own (0 where it exceeds it).
  std::map<std::tuple<int, int, int64_t, int64_t>, double> stretch_offset_;
  std::map<std::pair<int, int>, double> pair_offset_;
  double median_offset_ = 0;
  // Per cell of a border's band (a, b, cell x, cell y), the offset z_a - z_b
  // of the cells around it; none where it exceeds kCellMaxOffsets times
  // max_offset (seam_leveling.cc).
  std::map<std::tuple<int, int, int64_t, int64_t>, double> cell_offset_;
};

}  // namespace sapmvs

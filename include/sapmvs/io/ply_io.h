#pragma once
// Dense clouds in and out as PLY, the format mesh and point-cloud tools
// (CloudCompare, MeshLab, Open3D, PDAL) all read. The writer produces what
// the matcher stores as cloud.ply; the reader accepts what such tools write.
//
// Coordinates are kept in double throughout: a UTM northing (~5.4e6 m) in
// float32 would be quantised to 0.5 m.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sapmvs {

// One point of a dense cloud.
struct CloudPoint {
  // World coordinates, in the units of the cloud's CRS.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  // Unit surface normal in the world frame; zero when unknown.
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
  // 8-bit RGB.
  std::array<uint8_t, 3> color{{0, 0, 0}};
  // Photo-consistency of the point's patch (mean NCC over its views, -1..1).
  float score = 0;
  // Number of images the point was matched in.
  int num_views = 0;
};

struct PointCloud {
  std::vector<CloudPoint> points;
  // Which of the optional fields carry data (the writer stores only these;
  // the reader sets them from the properties the file declares).
  bool has_normals = false;
  bool has_colors = false;
  bool has_scores = false;
  bool has_views = false;
  // The coordinates' CRS (WKT, "EPSG:n" or a PROJ string) as given; empty
  // when unknown. Stored in the header as one `comment crs ...` line.
  std::string crs;
};

// Writes binary little-endian PLY, atomically: one `vertex` element with
// double x y z, then float nx ny nz, uchar red green blue, float scalar_score
// and scalar_views (uchar when every count is at most 255, else int), each
// group only
// when its has_* flag is set. Score and views are named `scalar_*` because
// CloudCompare, in command-line mode, keeps only properties so named (as
// scalar fields) and drops the rest. Line breaks in `crs` become spaces so that the
// comment stays one header line. Throws sapmvs::Error naming `path` and the
// point at fault (a non-finite coordinate, a negative view count) before
// anything is written.
void WritePly(const std::filesystem::path& path, const PointCloud& cloud);

// Reads ascii, binary_little_endian and binary_big_endian PLY 1.0. From the
// `vertex` element: x y z (any scalar type, usually float or double), and when
// declared nx ny nz, red green blue (uchar; ushort is scaled to 8 bit), score
// and views (any scalar type; named scalar_score and scalar_views, as written
// since, or score and views, as written before and by PMVS-style tools). Other vertex properties,
// lists included, are skipped by their declared type; elements before `vertex` are skipped, those
// after it are not read. A `comment crs ...` line fills `crs`.
// Throws sapmvs::InputError naming the file (and the header line, or the data
// line of an ascii file) when the header is malformed, there is no vertex
// element or no x y z, the data is truncated, or a coordinate is not finite.
// With `keep`, only the points whose position it returns true for are kept,
// in file order: a caller that needs part of a large cloud never holds the
// rest. Each point's position is shown to `keep` once, after it is checked
// to be finite; in a binary file of fixed-size records the rest of a point
// `keep` drops is not read (the tiled merge reads a group's cloud once per
// tile it meets).
using PointFilter = std::function<bool(const Eigen::Vector3d& position)>;
PointCloud ReadPly(const std::filesystem::path& path, const PointFilter& keep = {});

}  // namespace sapmvs

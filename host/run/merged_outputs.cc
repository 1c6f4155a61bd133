#include "run/merged_outputs.h"

#include <algorithm>
#include <future>

#include "run/point_spill.h"
#include "run/streamed_dsm.h"
#include "sapmvs/io/ply_stream.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/run/cloud_las.h"
#include "sapmvs/run/dsm_picture.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// MeanPointSpacing's sample count.
constexpr size_t kSpacingSamples = 200000;

}  // namespace

GeoRaster WriteMergedOutputs(const MergedOutputsJob& job, RunReport* report,
                             const std::function<void(const std::string&)>& end_stage) {
  const std::filesystem::path ply = job.out / "cloud.ply", las = job.out / "cloud.las";
  PointSpill spill(job.out);
  PointCloud format;
  PlyCounts ply_counts;
  LasCounts las_counts;
  std::vector<LasExtraField> las_ranges;
  SpacingSum spacing;
  // The first merged point (the footprint's grid origin, as MeasureFootprint
  // takes it) and the bounds.
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  MergeLayout layout;
  report->merge = MergeInTiles(
      job.groups, job.merge,
      [&](const PointCloud& tile, const MergeLayout& l) {
        if (spill.size() == 0) {
          format = l.format;
          if (format.crs.empty()) format.crs = job.crs;
          first = lo = hi = tile.points.front().position;
        }
        for (const CloudPoint& p : tile.points) {
          ply_counts.Add(ply.string(), p, format.has_views);
          lo = lo.cwiseMin(p.position);
          hi = hi.cwiseMax(p.position);
        }
        // In chunks, as the writer later takes them: a tile's records and
        // extra fields at once were a third of the merge's peak.
        PointCloud chunk = l.format;
        for (size_t at = 0; at < tile.points.size(); at += PointSpill::kChunk) {
          const size_t end = std::min(tile.points.size(), at + PointSpill::kChunk);
          chunk.points.assign(tile.points.begin() + at, tile.points.begin() + end);
          for (const PointRecord& r : ToLasRecords(chunk)) las_counts.Add(las, r, job.las.version);
          WidenExtraRanges(las, ToLasExtras(chunk), chunk.points.size(), &las_ranges);
        }
        // MeanPointSpacing's stride over the whole cloud: exact for one tile;
        // over several, from the input count, which the merge's duplicates
        // make a little larger than the output. Neighbours across a tile
        // border are missed, which raises the mean by about the share of
        // border points (under 1 % for tiles of 10^5 points and more).
        const size_t n = l.tiles() == 1 ? tile.points.size() : static_cast<size_t>(l.input_points);
        const SpacingSum s = SumPointSpacing(tile, std::max<size_t>(1, n / kSpacingSamples));
        spacing.sum += s.sum;
        spacing.samples += s.samples;
        spill.Append(tile.points);
      },
      &layout);
  report->merge_tiles = layout.tiles();
  end_stage("merge");
  if (spill.size() == 0) {
    throw Error(job.block.string() +
                ": no point survived matching and filtering; nothing "
                "written (check the orientation, or lower --threshold)");
  }
  report->points = static_cast<long>(spill.size());
  report->bounds_min = lo;
  report->bounds_max = hi;
  report->mean_spacing = spacing.samples > 0 ? spacing.sum / spacing.samples : 0;

  const double cell = DsmCellSize(job.dsm, report->mean_spacing);
  StreamedDsm dsm_bands(first, lo.x(), lo.y(), hi.x(), hi.y(), cell, format.crs, report->points,
                        job.out);
  NextPoints next = spill.Read();
  for (PointSpan s = next(); s.size > 0; s = next()) dsm_bands.Add(s);
  const CloudFootprint fp = dsm_bands.Footprint();
  const GeoRaster dsm = dsm_bands.Finish(job.dsm.fill_passes);
  report->dsm_cell = cell;
  report->area = fp.area;
  report->density = fp.density;
  end_stage("statistics");

  // The three writers read the spill each on its own and share nothing, so
  // they run side by side: one after the other they were the run's last
  // serial stage. The readers are opened here, as Read flushes the spill.
  NextPoints ply_next = spill.Read();
  NextPoints las_next = spill.Read();
  std::future<void> ply_done = std::async(
      std::launch::async, [&] { WritePlyStream(ply, format, ply_counts, std::move(ply_next)); });
  std::future<void> dsm_done = std::async(std::launch::async, [&] {
    WriteGeoTiff(job.out / "dsm.tif", dsm);
    WriteDsmPictures(dsm, job.out / "dsm_color.tif", job.out / "dsm.png");
  });
  PointCloud chunk = format;
  std::vector<PointRecord> records;
  std::vector<LasExtraField> extras;
  WriteLasStream(
      las, las_counts, job.las, las_ranges,
      [&](const std::vector<PointRecord>** points, const std::vector<LasExtraField>** fields) {
        const PointSpan s = las_next();
        if (s.size == 0) return false;
        chunk.points.assign(s.data, s.data + s.size);
        records = ToLasRecords(chunk);
        extras = ToLasExtras(chunk);
        *points = &records;
        *fields = &extras;
        return true;
      });
  ply_done.get();
  dsm_done.get();
  end_stage("write");
  return dsm;
}

}  // namespace sapmvs

#include "match/group_data.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/block/level_images.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/match/match_group.h"
#include "sapmvs/match/matcher_options.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/kernel_limits.h"
#include "sapmvs/util/parallel_for.h"
#include "util/image_codec.h"

namespace sapmvs {

double TriangulationAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& x) {
  const Eigen::Vector3d ra = (a - x).normalized();
  const Eigen::Vector3d rb = (b - x).normalized();
  return std::acos(std::clamp(ra.dot(rb), -1.0, 1.0)) * 180.0 / M_PI;
}

double GdalBytesToMatch(const Block& block) {
  for (const BlockImage& image : block.images)
    if (!DecodedWithoutGdal(image.path)) return GdalBytesToLoad();
  return 0;
}

MatchGroupData LoadMatchGroup(const Block& block, const std::vector<int>& ids, int level,
                              const BlockGeometry* known_geometry, const LevelImageStore* levels) {
  const LevelImageStore& store = StoreOrNone(levels);
  MatchGroupData group;
  group.origin = block.origin;
  const BlockGeometry geometry = known_geometry ? *known_geometry : EstimateBlockGeometry(block);
  std::vector<double> valid_depths;
  for (const int id : ids) {
    if (geometry.images.size() > static_cast<size_t>(id) && geometry.images[id].valid) {
      valid_depths.push_back(geometry.images[id].depth);
    }
  }
  double fallback_depth = 0;
  if (!valid_depths.empty()) {
    std::nth_element(valid_depths.begin(), valid_depths.begin() + valid_depths.size() / 2,
                     valid_depths.end());
    fallback_depth = valid_depths[valid_depths.size() / 2];
  }
  const double scale = std::ldexp(1.0, -level);
  std::vector<double> gsds;
  std::vector<cv::Mat> grey8(ids.size());
  // kImagesReadAtOnce side by side: the plan counts that many full-resolution
  // images (grouping.h EstimateGroupMemory).
  std::vector<MatchImage> images(ids.size());
  ParallelFor(
      static_cast<long>(ids.size()),
      [&](long k) {
        const int id = ids[k];
        const BlockImage& bi = block.images.at(id);
        MatchImage& im = images[k];
        im.name = bi.name;
        im.block_index = id;
        // The pinhole camera LoadUndistorted gives the pixels.
        im.camera = bi.camera.Pinhole().Scaled(scale).Translated(block.origin);
        const cv::Mat bgr = store.Load(bi, level, im.camera.width(), im.camera.height());
        im.file = FileStamp::Of(bi.path).value_or(FileStamp{});
        cv::cvtColor(bgr, grey8[k], cv::COLOR_BGR2GRAY);
      },
      1, kImagesReadAtOnce);
  for (size_t k = 0; k < ids.size(); ++k) {
    const int id = ids[k];
    MatchImage& im = images[k];
    const bool have = geometry.images.size() > static_cast<size_t>(id) && geometry.images[id].valid;
    im.depth = have ? geometry.images[id].depth : fallback_depth;
    if (im.depth > 0) gsds.push_back(im.depth / im.camera.intrinsics().MeanFocal());
    group.images.push_back(std::move(im));
  }
  if (group.images.size() < 2)
    throw Error("matching needs at least 2 images, got " + std::to_string(group.images.size()));
  if (!gsds.empty()) {
    std::nth_element(gsds.begin(), gsds.begin() + gsds.size() / 2, gsds.end());
    group.gsd = gsds[gsds.size() / 2];
  }
  // Every grey image in one block, rows packed, in the order and at the
  // offsets of the kernels' image buffer (UploadNccGroup), so that a device
  // sharing the host's memory reads them in place. group.ncc.pixels owns it
  // (MatchImage::grey); it starts on a page boundary, which any device's
  // base address alignment divides.
  constexpr size_t kPage = 4096;
  size_t total = 0;
  for (const cv::Mat& g : grey8) total += g.total();
  // Not a cv::Mat: its int columns would cap a group at 2^31 pixels, which
  // only the OpenCL devices' int offsets need to (UploadNccGroup says so).
  const size_t bytes = (total * sizeof(float) + kPage - 1) / kPage * kPage;
  float* block_start = static_cast<float*>(std::aligned_alloc(kPage, bytes));
  if (block_start == nullptr) {
    throw Error("cannot allocate " + std::to_string(bytes) + " bytes for the group's " +
                std::to_string(group.images.size()) + " grey images");
  }
  group.ncc.pixels = std::shared_ptr<const float>(
      block_start, [](const float* p) { std::free(const_cast<float*>(p)); });
  size_t offset = 0;
  for (size_t i = 0; i < group.images.size(); ++i) {
    // A header over the block, not a region of it: OpenCV's filters read
    // past a region's edges into its parent (the images beside it) instead
    // of extrapolating the border. MatchImage::grey shares the block's
    // lifetime through group.ncc.pixels.
    cv::Mat in_block(grey8[i].rows, grey8[i].cols, CV_32F, block_start + offset);
    grey8[i].convertTo(in_block, CV_32F);
    group.images[i].grey = in_block;
    offset += grey8[i].total();
    grey8[i].release();
  }
  for (const MatchImage& im : group.images) {
    FloatImageView view;
    view.data = im.grey.ptr<float>();
    view.layout.width = im.grey.cols;
    view.layout.height = im.grey.rows;
    view.layout.row_pitch = static_cast<int>(im.grey.step1());
    group.ncc.images.push_back(view);
    group.ncc.cameras.push_back(MakeNccCamera(im.camera, im.name.c_str()));
  }
  return group;
}

cv::Mat LoadColorAtLevel(const Block& block, const MatchImage& image, int level,
                         const LevelImageStore* levels) {
  const BlockImage& bi = block.images.at(image.block_index);
  // A file that cannot be stamped now is left to the read, which names
  // what is wrong with it.
  const std::optional<FileStamp> now = FileStamp::Of(bi.path);
  if (now && *now != image.file) {
    throw Error(bi.path.string() +
                ": image file changed while its group was matched (expected the file that "
                "was loaded: its points take their colours from it)");
  }
  return StoreOrNone(levels).Load(bi, level, image.camera.width(), image.camera.height());
}

void SelectViews(const MatcherOptions& /*options*/, MatchGroupData* group) {
  // Below this, a view is a copy of the reference's viewpoint.
  constexpr double kMinViewAngleDeg = 0.1;
  auto& images = group->images;
  // Without any surface estimate, fall back on a depth that gives the
  // neighbours a plausible baseline: the median distance to the nearest centre
  // times 2.5 (60 % overlap of a nadir block).
  for (MatchImage& im : images) {
    if (im.depth > 0) continue;
    double nearest = 1e300;
    for (const MatchImage& other : images) {
      if (&other == &im) continue;
      nearest = std::min(nearest, (other.camera.center() - im.camera.center()).norm());
    }
    im.depth = 2.5 * nearest;
  }
  constexpr int kGrid = 7;
  for (size_t i = 0; i < images.size(); ++i) {
    MatchImage& im = images[i];
    const Camera& cam = im.camera;
    const Eigen::Vector3d axis_point = cam.BackProject(
        Eigen::Vector2d(0.5 * (cam.width() - 1), 0.5 * (cam.height() - 1)), im.depth);
    std::vector<std::pair<double, int>> ranked;
    for (size_t j = 0; j < images.size(); ++j) {
      if (j == i) continue;
      const Camera& other = images[j].camera;
      // A view from (almost) the same place adds no depth; narrow views do,
      // together with the others (PatchEngine::WideEnough), so they stay.
      if (TriangulationAngleDeg(cam.center(), other.center(), axis_point) < kMinViewAngleDeg) {
        continue;
      }
      int inside = 0;
      for (int gy = 0; gy < kGrid; ++gy) {
        for (int gx = 0; gx < kGrid; ++gx) {
          const Eigen::Vector2d uv((gx + 0.5) * cam.width() / kGrid,
                                   (gy + 0.5) * cam.height() / kGrid);
          const Eigen::Vector3d x = cam.BackProject(uv, im.depth);
          if (other.Depth(x) > 0 && other.InImage(other.Project(x))) ++inside;
        }
      }
      const double overlap = static_cast<double>(inside) / (kGrid * kGrid);
      if (overlap >= 0.1) ranked.emplace_back(overlap, static_cast<int>(j));
    }
    // The group's own images first, then another strip's view-only ones:
    // those only fill (PatchEngine::VisibleViews), so with more than
    // kMaxViews - 1 candidates (--max-images 7 or more with --strip-views)
    // one must not push an own image out. Each part by overlap.
    std::sort(ranked.begin(), ranked.end(), [&](const auto& a, const auto& b) {
      const bool own_a = images[a.second].reference, own_b = images[b.second].reference;
      if (own_a != own_b) return own_a;
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    im.views.clear();
    for (const auto& r : ranked) {
      if (static_cast<int>(im.views.size()) >= kMaxViews - 1) break;
      im.views.push_back(r.second);
    }
  }
}

}  // namespace sapmvs

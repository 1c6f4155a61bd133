#include "sapmvs/ortho/true_ortho.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <string>

#include "ortho/ortho_depth_buffer.h"
#include "ortho/ortho_surface.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/block/level_images.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/parallel_for.h"
#include "sapmvs/util/thread_count.h"

namespace sapmvs {
namespace {

// Objects and the ground this many cells around them go with their image,
// beyond the blend, so that the blend stays on open ground.
constexpr int kObjectMarginCells = 2;
// A point on the drawn DSM surface lies behind the depth at its nearest
// pixel by at most this many DSM cells (the surface's slope over half a
// pixel); a cell's centre at a wall's foot lies half a cell from the wall,
// and at least as far behind it in a view that looks over the wall at it.
constexpr double kSeenToleranceCells = 0.5;
// Gaps no image sees are inpainted up to this many cells from a colour.
constexpr int kGapCells = 4;
// Images decoded, and depth buffers held, at once, at most.
constexpr int kImagesAtOnce = 4;

struct OrthoView {
  int image = 0;
  Camera camera;         // pinhole, at the level
  CellWindow cells;      // of the ortho grid
  CellWindow dsm_cells;  // of the DSM
};

// The cosine of the ray's angle to the vertical: how directly the image
// looks at the point from above.
float Directness(const Camera& camera, const Eigen::Vector3d& x) {
  return static_cast<float>((camera.center() - x).normalized().z());
}

Eigen::Vector3d CellPoint(const GeoRaster& grid, int col, int row) {
  const Eigen::Vector2d xy = grid.CellCenter(col, row);
  return {xy.x(), xy.y(), grid.at(col, row)};
}

// For each object, the view that looks at its centre most directly among
// those whose image holds the centre: the view nearest overhead sees the
// most of an object's sides as it is on the map. -1 for an object no view
// holds.
std::vector<int> ChooseObjectViews(const OrthoSurface& surface,
                                   const std::vector<OrthoView>& views) {
  const GeoRaster& dsm = surface.dsm;
  std::vector<Eigen::Vector4d> sums(surface.objects, Eigen::Vector4d::Zero());
  for (int r = 0; r < dsm.height; ++r) {
    for (int c = 0; c < dsm.width; ++c) {
      const int o = surface.dsm_object[static_cast<size_t>(r) * dsm.width + c];
      if (o < 0 || dsm.IsEmpty(c, r)) continue;
      const Eigen::Vector3d x = CellPoint(dsm, c, r);
      sums[o] += Eigen::Vector4d(x.x(), x.y(), x.z(), 1);
    }
  }
  std::vector<int> chosen(surface.objects, -1);
  for (int o = 0; o < surface.objects; ++o) {
    if (sums[o].w() == 0) continue;
    const Eigen::Vector3d centre = sums[o].head<3>() / sums[o].w();
    float top = 0;
    for (size_t k = 0; k < views.size(); ++k) {
      if (!views[k].camera.InImage(views[k].camera.Project(centre))) continue;
      const float s = Directness(views[k].camera, centre);
      if (s > top) {
        top = s;
        chosen[o] = static_cast<int>(k);
      }
    }
  }
  return chosen;
}

// Cells on the DSM that no image sees, within kGapCells of cells that one
// does: slivers at the foot of walls, where the DSM's step from the ground
// to the roof spans a cell and hides them from every view. Inpainted from
// around them (OpenCV's Telea) rather than left as holes along every roof;
// tile by tile, as Telea's cost and its copies grow with the whole image.
long FillGaps(const GeoRaster& grid, std::vector<uint8_t>* rgba) {
  constexpr int kTile = 256, kMargin = 2 * kGapCells;
  std::vector<cv::Rect> tiles;
  for (int y = 0; y < grid.height; y += kTile) {
    for (int x = 0; x < grid.width; x += kTile)
      tiles.emplace_back(x, y, std::min(kTile, grid.width - x), std::min(kTile, grid.height - y));
  }
  // Read from the colours as they were, written after: a tile's margin is
  // its neighbours' cells.
  std::vector<std::vector<std::pair<size_t, cv::Vec3b>>> fills(tiles.size());
  ParallelFor(static_cast<long>(tiles.size()), [&](long t) {
    const cv::Rect tile = tiles[t];
    const cv::Rect box = (tile + cv::Size(2 * kMargin, 2 * kMargin) - cv::Point(kMargin, kMargin)) &
                         cv::Rect(0, 0, grid.width, grid.height);
    cv::Mat bgr(box.size(), CV_8UC3), has(box.size(), CV_8U), gap(box.size(), CV_8U);
    bool any = false;
    for (int r = 0; r < box.height; ++r) {
      for (int c = 0; c < box.width; ++c) {
        const int gc = box.x + c, gr = box.y + r;
        const uint8_t* p = &(*rgba)[4 * (static_cast<size_t>(gr) * grid.width + gc)];
        bgr.at<cv::Vec3b>(r, c) = cv::Vec3b(p[2], p[1], p[0]);
        has.at<uint8_t>(r, c) = p[3] ? 255 : 0;
        const bool g = !p[3] && !std::isnan(grid.at(gc, gr));
        gap.at<uint8_t>(r, c) = g ? 255 : 0;
        any = any || (g && tile.contains({gc, gr}));
      }
    }
    if (!any) return;
    cv::Mat near;
    cv::dilate(
        has, near,
        cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * kGapCells + 1, 2 * kGapCells + 1)));
    gap &= near;
    if (cv::countNonZero(gap) == 0) return;
    cv::Mat painted;
    cv::inpaint(bgr, gap, painted, kGapCells, cv::INPAINT_TELEA);
    // Only the tile's own cells: its neighbours write theirs.
    for (int gr = tile.y; gr < tile.y + tile.height; ++gr) {
      for (int gc = tile.x; gc < tile.x + tile.width; ++gc) {
        const int r = gr - box.y, c = gc - box.x;
        if (!gap.at<uint8_t>(r, c)) continue;
        fills[t].emplace_back(static_cast<size_t>(gr) * grid.width + gc,
                              painted.at<cv::Vec3b>(r, c));
      }
    }
  });
  long n = 0;
  for (const auto& tile : fills) {
    for (const auto& [i, v] : tile) {
      uint8_t* q = &(*rgba)[4 * i];
      q[0] = v[2], q[1] = v[1], q[2] = v[0], q[3] = 255;
    }
    n += static_cast<long>(tile.size());
  }
  return n;
}

}  // namespace

TrueOrtho MakeTrueOrtho(const Block& block, const GeoRaster& source_dsm, int level,
                        const OrthoOptions& options, double default_cell,
                        const std::function<void(int, int)>& progress,
                        const LevelImageStore* levels) {
  const LevelImageStore& store = StoreOrNone(levels);
  if (const std::string p = options.Problem(); !p.empty()) {
    throw Error("orthophoto: expected " + p);
  }
  const double cell = options.cell_size > 0 ? options.cell_size : default_cell;
  if (!(cell > 0)) throw Error("orthophoto: the cell size is 0 (give --ortho-cell)");
  const double margin = (kObjectMarginCells + options.blend_cells) * cell;
  const OrthoSurface surface = MakeOrthoSurface(source_dsm, cell, options.object_slope, margin);
  const GeoRaster& grid = surface.grid;
  const GeoRaster& dsm = surface.dsm;
  const double tolerance = kSeenToleranceCells * dsm.cell_size;

  std::vector<OrthoView> views;
  for (size_t i = 0; i < block.images.size(); ++i) {
    OrthoView v;
    v.image = static_cast<int>(i);
    v.camera = block.images[i].camera.Pinhole().Scaled(std::ldexp(1.0, -level));
    v.cells = ImageWindow(v.camera, grid, surface.zmin, surface.zmax);
    v.dsm_cells = ImageWindow(v.camera, dsm, surface.zmin, surface.zmax);
    if (!v.cells.Empty()) views.push_back(v);
  }

  const std::vector<int> object_view = ChooseObjectViews(surface, views);

  // Each DSM cell's most direct view among those that see it, and the
  // object's view where that one sees it. On the DSM's cells: the DSM
  // decides what each image sees, and the blend below smooths the seams
  // between its cells. The views run side by side, each drawing its own
  // depth buffer (at most kImagesAtOnce of them: a 20 MP image's at level 0
  // is 80 MB); a cell's best (directness, view) is one 64-bit word that
  // they raise atomically: a positive float's bits order as the float.
  const size_t dsm_cells = dsm.values.size();
  std::vector<std::atomic<uint64_t>> best(dsm_cells);
  for (auto& b : best) b.store(0, std::memory_order_relaxed);
  std::vector<int> object_label(dsm_cells, -1);
  ParallelFor(
      static_cast<long>(views.size()),
      [&](long k) {
        const OrthoView& v = views[k];
        const OrthoDepthBuffer depth(v.camera, dsm, v.dsm_cells, surface.walls, tolerance);
        for (int r = v.dsm_cells.row0; r < v.dsm_cells.row1; ++r) {
          for (int c = v.dsm_cells.col0; c < v.dsm_cells.col1; ++c) {
            if (dsm.IsEmpty(c, r)) continue;
            const Eigen::Vector3d x = CellPoint(dsm, c, r);
            Eigen::Vector2d uv;
            if (!depth.Sees(x, &uv)) continue;
            const size_t at = static_cast<size_t>(r) * dsm.width + c;
            const int object = surface.dsm_object[at];
            // Only this view writes its objects' cells.
            if (object >= 0 && object_view[object] == k) object_label[at] = static_cast<int>(k);
            // Directness is in (0, 1] where a view sees the cell from above.
            const float s = std::max(Directness(v.camera, x), 1e-6f);
            uint32_t bits;
            std::memcpy(&bits, &s, sizeof bits);
            const uint64_t word = (static_cast<uint64_t>(bits) << 32) | static_cast<uint32_t>(k);
            uint64_t old = best[at].load(std::memory_order_relaxed);
            while (word > old &&
                   !best[at].compare_exchange_weak(old, word, std::memory_order_relaxed)) {
            }
          }
        }
      },
      1, kImagesAtOnce);
  std::vector<int> label(dsm_cells, -1);
  for (size_t i = 0; i < dsm_cells; ++i) {
    const uint64_t word = best[i].load(std::memory_order_relaxed);
    label[i] = object_label[i] >= 0 ? object_label[i]
               : word != 0          ? static_cast<int>(word & 0xffffffffu)
                                    : -1;
  }
  std::vector<std::atomic<uint64_t>>().swap(best);
  object_label = {};
  // Colours: each view's pixels weighted by the count of its label in the
  // (2b+1)^2 cells around, where the view sees the cell. The weights at a
  // cell add up to at most (2b+1)^2, so the sums of 8-bit values fit 16
  // bits for b <= 7 (OrthoOptions::blend_cells).
  const int b = options.blend_cells;
  const int side = 2 * b + 1;
  const size_t cells = grid.values.size();
  std::vector<uint16_t> sum(4 * cells, 0);
  std::vector<bool> used(views.size(), false);
  for (const int k : label) {
    if (k >= 0) used[k] = true;
  }
  std::vector<int> used_views;
  for (size_t k = 0; k < views.size(); ++k) {
    if (used[k]) used_views.push_back(static_cast<int>(k));
  }
  auto label_at = [&](int col, int row) {
    return label[static_cast<size_t>(surface.dsm_row[row]) * dsm.width + surface.dsm_col[col]];
  };
  // Images are decoded a few at once, one per thread: decoding and
  // undistorting are most of this pass, and each is serial. More at once
  // would only hold more images.
  const int batch = std::max(1, std::min(HostThreadCount(), kImagesAtOnce));
  int done = 0;
  for (size_t first = 0; first < used_views.size(); first += batch) {
    const size_t n = std::min(used_views.size() - first, static_cast<size_t>(batch));
    std::vector<cv::Mat> loaded(n);
    std::vector<std::unique_ptr<OrthoDepthBuffer>> depths(n);
    ParallelFor(
        static_cast<long>(n),
        [&](long j) {
          const OrthoView& v = views[used_views[first + j]];
          loaded[j] =
              store.Load(block.images[v.image], level, v.camera.width(), v.camera.height(), false);
          depths[j] = std::make_unique<OrthoDepthBuffer>(v.camera, dsm, v.dsm_cells, surface.walls,
                                                         tolerance);
        },
        1);
    for (size_t j = 0; j < n; ++j) {
      const int k = used_views[first + j];
      const cv::Mat& pixels = loaded[j];
      const OrthoView& v = views[k];
      const OrthoDepthBuffer& depth = *depths[j];
      // The count of the view's label around each cell of its window.
      const cv::Rect rect(v.cells.col0, v.cells.row0, v.cells.col1 - v.cells.col0,
                          v.cells.row1 - v.cells.row0);
      cv::Mat mine(rect.height + 2 * b, rect.width + 2 * b, CV_8U, cv::Scalar(0));
      ParallelFor(rect.height + 2 * b, [&](long i) {
        const int gr = rect.y + static_cast<int>(i) - b;
        if (gr < 0 || gr >= grid.height) return;
        uint8_t* row = mine.ptr<uint8_t>(static_cast<int>(i));
        for (int c = 0; c < rect.width + 2 * b; ++c) {
          const int gc = rect.x + c - b;
          if (gc >= 0 && gc < grid.width && label_at(gc, gr) == k) row[c] = 1;
        }
      });
      cv::Mat count;
      cv::boxFilter(mine, count, CV_16U, cv::Size(side, side), cv::Point(-1, -1), false,
                    cv::BORDER_CONSTANT);
      ParallelFor(rect.height, [&](long i) {
        const int r = static_cast<int>(i), gr = rect.y + r;
        const uint16_t* weights = count.ptr<uint16_t>(r + b) + b;
        for (int c = 0; c < rect.width; ++c) {
          const int w = weights[c];
          const int gc = rect.x + c;
          if (w == 0 || std::isnan(grid.at(gc, gr))) continue;
          Eigen::Vector2d uv;
          if (!depth.Sees(CellPoint(grid, gc, gr), &uv)) continue;
          const Eigen::Vector3d bgr = BilinearBgr(pixels, uv.x(), uv.y());
          uint16_t* s = &sum[4 * (static_cast<size_t>(gr) * grid.width + gc)];
          for (int ch = 0; ch < 3; ++ch)
            s[ch] += static_cast<uint16_t>(std::lround(w * bgr[2 - ch]));
          s[3] += static_cast<uint16_t>(w);
        }
      });
      if (progress) progress(++done, static_cast<int>(used_views.size()));
    }
  }

  TrueOrtho out;
  out.grid = grid;
  out.grid.values = {};
  out.rgba.assign(4 * cells, 0);
  for (size_t i = 0; i < cells; ++i) {
    const uint16_t* s = &sum[4 * i];
    if (s[3] == 0) continue;
    for (int ch = 0; ch < 3; ++ch)
      out.rgba[4 * i + ch] = static_cast<uint8_t>((s[ch] + s[3] / 2) / s[3]);
    out.rgba[4 * i + 3] = 255;
    ++out.filled_cells;
  }
  sum = {};
  out.inpainted_cells = FillGaps(grid, &out.rgba);
  out.filled_cells += out.inpainted_cells;
  out.images_used = static_cast<int>(used_views.size());
  out.objects = surface.objects;
  return out;
}

}  // namespace sapmvs

#include "sapmvs/block/tie_points.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <system_error>
#include <thread>

#include "sapmvs/block/image_io.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/memory_use.h"
#include "sapmvs/util/parallel_for.h"

namespace sapmvs {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Half of Lowe's 0.04: hazy aerial scans and the simulator's renderings have
// little contrast, and at 0.04 SIFT found a third as many features on `tiny`
// (550 of 1,500 asked for) and almost no matches between strips flown in
// opposite directions. The feature count still keeps the strongest.
constexpr double kContrastThreshold = 0.02;

struct ImageFeatures {
  bool valid = false;
  Camera camera;  // local frame, reduced size, no distortion
  std::vector<Eigen::Vector2d> uv;
  cv::Mat descriptors;  // CV_32F, one row per feature
};

ImageFeatures Detect(const BlockImage& image, const Eigen::Vector3d& origin,
                     const TiePointOptions& o) {
  ImageFeatures out;
  const LoadedImage loaded = LoadUndistorted(image);
  int level = 0;
  Camera camera = loaded.camera;
  while (std::max(camera.width(), camera.height()) > o.max_side) {
    camera = loaded.camera.Scaled(std::ldexp(1.0, -++level));
  }
  const cv::Mat bgr = ResampleToLevel(loaded.pixels, level, camera.width(), camera.height());
  out.camera = camera.Translated(origin);
  cv::Mat grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::SIFT::create(o.features, 3, kContrastThreshold)
      ->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  // SIFT repeats a keypoint for each dominant orientation; the copies would
  // fail every ratio test against each other and join tracks twice.
  std::vector<int> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return keypoints[a].response > keypoints[b].response; });
  std::vector<int> kept;
  for (const int k : order) {
    const Eigen::Vector2d uv(keypoints[k].pt.x, keypoints[k].pt.y);
    const bool repeat = std::any_of(kept.begin(), kept.end(), [&](int q) {
      return (Eigen::Vector2d(keypoints[q].pt.x, keypoints[q].pt.y) - uv).squaredNorm() < 0.25;
    });
    if (repeat) continue;
    kept.push_back(k);
  }
  out.descriptors = cv::Mat(static_cast<int>(kept.size()), descriptors.cols, CV_32F);
  for (size_t r = 0; r < kept.size(); ++r) {
    descriptors.row(kept[r]).copyTo(out.descriptors.row(static_cast<int>(r)));
    out.uv.emplace_back(keypoints[kept[r]].pt.x, keypoints[kept[r]].pt.y);
  }
  out.valid = true;
  return out;
}

// F with x_b^T F x_a = 0, from the cameras: F = K_b^-T [t]x R K_a^-1, R and t
// taking camera a's frame to camera b's.
Eigen::Matrix3d Fundamental(const Camera& a, const Camera& b) {
  const Eigen::Matrix3d r = b.rotation() * a.rotation().transpose();
  const Eigen::Vector3d t = b.rotation() * (a.center() - b.center());
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  return b.intrinsics().K().inverse().transpose() * tx * r * a.intrinsics().K().inverse();
}

// The point nearest (least squares) to the rays of `cameras` through `uvs`;
// NaN when the rays are (near) parallel.
Eigen::Vector3d Triangulate(const std::vector<const Camera*>& cameras,
                            const std::vector<Eigen::Vector2d>& uvs) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < cameras.size(); ++k) {
    const Eigen::Vector3d d = cameras[k]->Ray(uvs[k]);
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - d * d.transpose();
    a += p;
    b += p * cameras[k]->center();
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(a);
  if (lu.rank() < 3) return Eigen::Vector3d::Constant(std::nan(""));
  return lu.solve(b);
}

// Matches of a's features in b (pairs of feature indices): the nearest
// descriptor within epipolar_px of the epipolar line, in front of both
// cameras, passing the ratio test against the next such candidate at another
// place, and the best of a's features for that feature of b. Only the
// features in the epipolar band are compared: a brute-force nearest
// neighbour over all of b took 80 % of the stage's time for the few
// candidates the band leaves.
std::vector<std::pair<int, int>> MatchPair(const ImageFeatures& a, const ImageFeatures& b,
                                           const TiePointOptions& o) {
  std::vector<std::pair<int, int>> out;
  if (a.descriptors.empty() || b.descriptors.empty()) return out;
  const Eigen::Matrix3d f = Fundamental(a.camera, b.camera);
  const int dims = a.descriptors.cols;
  std::vector<std::pair<float, int>> best_for_b(b.uv.size(), {1e30f, -1});
  std::vector<std::pair<float, int>> band;
  for (int qa = 0; qa < static_cast<int>(a.uv.size()); ++qa) {
    const Eigen::Vector3d line = f * a.uv[qa].homogeneous();
    const double norm = line.head<2>().norm();
    if (!(norm > 0)) continue;
    const double reach = o.epipolar_px * norm;
    const float* da = a.descriptors.ptr<float>(qa);
    band.clear();
    for (int j = 0; j < static_cast<int>(b.uv.size()); ++j) {
      if (std::abs(line.x() * b.uv[j].x() + line.y() * b.uv[j].y() + line.z()) > reach) continue;
      band.emplace_back(cv::hal::normL2Sqr_(da, b.descriptors.ptr<float>(j), dims), j);
    }
    if (band.empty()) continue;
    std::sort(band.begin(), band.end());
    const Eigen::Vector3d x = Triangulate({&a.camera, &b.camera}, {a.uv[qa], b.uv[band[0].second]});
    if (!(a.camera.Depth(x) > 0 && b.camera.Depth(x) > 0)) continue;
    float next2 = 1e30f;
    for (size_t k = 1; k < band.size(); ++k) {
      if ((b.uv[band[k].second] - b.uv[band[0].second]).squaredNorm() > 4.0) {
        next2 = band[k].first;
        break;
      }
    }
    // Squared distances: the ratio applies to their square roots.
    if (!(band[0].first < o.ratio * o.ratio * next2)) continue;
    auto& best = best_for_b[band[0].second];
    if (band[0].first < best.first) best = {band[0].first, qa};
  }
  for (size_t j = 0; j < best_for_b.size(); ++j) {
    if (best_for_b[j].second >= 0) out.emplace_back(best_for_b[j].second, static_cast<int>(j));
  }
  return out;
}

// Pairs to match: each image with its `neighbours` nearest projection centres
// among the images looking the same way (optical axes within the angle).
std::vector<std::pair<int, int>> ChoosePairs(const std::vector<ImageFeatures>& images,
                                             const TiePointOptions& o) {
  std::vector<std::pair<int, int>> pairs;
  const double cos_max = std::cos(o.max_axis_angle_deg * kDeg);
  const int n = static_cast<int>(images.size());
  for (int i = 0; i < n; ++i) {
    if (!images[i].valid) continue;
    std::vector<std::pair<double, int>> near;
    for (int j = 0; j < n; ++j) {
      if (j == i || !images[j].valid) continue;
      const Camera &a = images[i].camera, &b = images[j].camera;
      if (a.ViewingDirection().dot(b.ViewingDirection()) < cos_max) continue;
      const double d = (a.center() - b.center()).norm();
      if (d > 0) near.emplace_back(d, j);
    }
    std::sort(near.begin(), near.end());
    for (size_t k = 0; k < near.size() && static_cast<int>(k) < o.neighbours; ++k) {
      pairs.emplace_back(std::min(i, near[k].second), std::max(i, near[k].second));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

int Find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

std::string TiePointOptions::Problem() const {
  std::ostringstream s;
  if (max_side < 64)
    s << "max_side >= 64 (max_side = " << max_side << ")";
  else if (features < 10)
    s << "features >= 10 (features = " << features << ")";
  else if (neighbours < 1)
    s << "neighbours >= 1 (neighbours = " << neighbours << ")";
  else if (!(max_axis_angle_deg > 0 && max_axis_angle_deg <= 180))
    s << "max_axis_angle_deg in (0, 180] (max_axis_angle_deg = " << max_axis_angle_deg << ")";
  else if (!(epipolar_px > 0 && epipolar_px <= 50))
    s << "epipolar_px in (0, 50] (epipolar_px = " << epipolar_px << ")";
  else if (!(ratio > 0 && ratio <= 1))
    s << "ratio in (0, 1] (ratio = " << ratio << ")";
  else if (min_views < 2)
    s << "min_views >= 2 (min_views = " << min_views << ")";
  else if (!(max_reprojection_px > 0 && max_reprojection_px <= 50))
    s << "max_reprojection_px in (0, 50] (max_reprojection_px = " << max_reprojection_px << ")";
  else if (!(min_angle_deg >= 0 && min_angle_deg < 90))
    s << "min_angle_deg in [0, 90) (min_angle_deg = " << min_angle_deg << ")";
  else if (concurrent_images < 1)
    s << "concurrent_images >= 1 (concurrent_images = " << concurrent_images << ")";
  return s.str();
}

std::vector<TiePoint> TriangulateTiePoints(const Block& block, const TiePointOptions& o) {
  if (const std::string p = o.Problem(); !p.empty())
    throw Error("tie point options: expected " + p);
  const int n = static_cast<int>(block.images.size());
  std::vector<ImageFeatures> images(n);
  std::vector<int> with_files;
  for (int i = 0; i < n; ++i) {
    if (!block.images[i].path.empty()) with_files.push_back(i);
  }
  if (with_files.size() < 2) return {};
  // At most concurrent_images at once: SIFT's pyramid of an image doubled
  // in size is about 60 MB at 600 px. OpenCV spreads each image's pyramid
  // and descriptors over the cores itself, but builds the Gaussian levels
  // and decodes the file on one: with one image at a time, 1.3 of 2 cores
  // were busy (`small`'s planning, 1.6 s of its 7).
  try {
    // SIFT's pyramids, built afresh for each image (RunWithHeapReuse).
    RunWithHeapReuse([&] {
      ParallelFor(
          static_cast<long>(with_files.size()),
          [&](long w) {
            images[with_files[w]] = Detect(block.images[with_files[w]], block.origin, o);
          },
          1, o.concurrent_images);
    });
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {  // OpenCV's, as one of ours
    throw Error(e.what());
  }

  const std::vector<std::pair<int, int>> pairs = ChoosePairs(images, o);
  std::vector<std::vector<std::pair<int, int>>> matches(pairs.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t p = 0; p < pairs.size(); ++p) {
    matches[p] = MatchPair(images[pairs[p].first], images[pairs[p].second], o);
  }

  // Tracks: features linked by any match, over all pairs.
  std::vector<int> offset(n + 1, 0);
  for (int i = 0; i < n; ++i) offset[i + 1] = offset[i] + static_cast<int>(images[i].uv.size());
  std::vector<int> parent(offset[n]);
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t p = 0; p < pairs.size(); ++p) {
    for (const auto& [fa, fb] : matches[p]) {
      const int ra = Find(parent, offset[pairs[p].first] + fa);
      const int rb = Find(parent, offset[pairs[p].second] + fb);
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
    }
  }
  std::vector<std::vector<int>> members(offset[n]);
  for (int i = 0; i < n; ++i) {
    for (int f = 0; f < offset[i + 1] - offset[i]; ++f) {
      const int node = offset[i] + f;
      members[Find(parent, node)].push_back(node);
    }
  }
  const int min_views = std::min(o.min_views, static_cast<int>(with_files.size()));
  const double cos_min_angle = std::cos(o.min_angle_deg * kDeg);
  std::vector<TiePoint> out;
  for (int root = 0; root < offset[n]; ++root) {
    const std::vector<int>& nodes = members[root];
    if (static_cast<int>(nodes.size()) < min_views) continue;
    std::vector<int> image_of;
    std::vector<const Camera*> cams;
    std::vector<Eigen::Vector2d> uvs;
    for (const int node : nodes) {
      const int i =
          static_cast<int>(std::upper_bound(offset.begin(), offset.end(), node) - offset.begin()) -
          1;
      image_of.push_back(i);
      cams.push_back(&images[i].camera);
      uvs.push_back(images[i].uv[node - offset[i]]);
    }
    // Two features of one image in a track: some match in it is wrong.
    std::vector<int> sorted = image_of;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) continue;
    // Drop the worst observation until all reproject well (or too few stay).
    Eigen::Vector3d x;
    while (true) {
      x = Triangulate(cams, uvs);
      if (!x.allFinite()) break;
      int worst = -1;
      double worst_error = o.max_reprojection_px;
      for (size_t k = 0; k < cams.size(); ++k) {
        const double e = cams[k]->Depth(x) > 0 ? (cams[k]->Project(x) - uvs[k]).norm() : 1e30;
        if (e > worst_error) worst_error = e, worst = static_cast<int>(k);
      }
      if (worst < 0) break;
      cams.erase(cams.begin() + worst);
      uvs.erase(uvs.begin() + worst);
      image_of.erase(image_of.begin() + worst);
      if (static_cast<int>(cams.size()) < min_views) break;
    }
    if (!x.allFinite() || static_cast<int>(cams.size()) < min_views) continue;
    double widest = 1;
    for (size_t a = 0; a < cams.size(); ++a) {
      for (size_t b = a + 1; b < cams.size(); ++b) {
        widest = std::min(
            widest, (cams[a]->center() - x).normalized().dot((cams[b]->center() - x).normalized()));
      }
    }
    if (widest > cos_min_angle) continue;
    TiePoint t;
    t.position = x + block.origin;
    t.images = image_of;
    std::sort(t.images.begin(), t.images.end());
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace sapmvs

#include "match/ncc_score_reference.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "match/footprint.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

// Twin of NCC_MIN_AXIS_LENGTH in kernels/ncc_score.cl: a kernel-internal
// geometric guard, not a tunable, so it is not passed as -D.
constexpr double kNccMinAxisLength = 1e-3;
constexpr size_t kMaxSamples = static_cast<size_t>(kMaxPatchSize) * kMaxPatchSize;

// Signed distance of (x, y) to the edge of [0, w - 1] x [0, h - 1]: positive
// inside, negative outside.
double BorderDistance(const ImageLayout& layout, double x, double y) {
  return std::min({x, y, (layout.width - 1) - x, (layout.height - 1) - y});
}

}  // namespace

double NccWeightScale(const double* values, int n, double sigma) {
  double mean = 0.0, var = 0.0;
  for (int k = 0; k < n; ++k) mean += values[k];
  mean /= n;
  for (int k = 0; k < n; ++k) var += std::pow(values[k] - mean, 2);
  return sigma * std::max(std::sqrt(var / n), static_cast<double>(kNccWeightMinSpread));
}

double NccScoreReferenceUnchecked(const NccGroup& group, const NccPatch& patch, int view,
                                  int patch_size, double sigma_color, double* border_margin,
                                  double sample_step) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const int half = patch_size / 2;
  const size_t num_samples = static_cast<size_t>(patch_size) * patch_size;
  // The kernel's sigma is a float literal.
  const double sigma = static_cast<float>(sigma_color);
  // On the stack: the CPU backend scores millions of pairs.
  std::array<double, kMaxSamples> a, b, weight;
  weight.fill(1.0);

  const int views[2] = {patch.reference, view};
  const NccCamera& ref = group.cameras[patch.reference];
  const Eigen::Vector3d c = Xyz(patch.center);
  const Eigen::Vector3d n = Xyz(patch.normal);
  const double depth = Xyzw(ref.p[2]).dot(c.homogeneous());
  if (!(depth > 0.0)) return nan;
  // The same plane test as the kernel (plane_seen in ncc.cl).
  const Eigen::Vector3d x_proj = Xyz(ref.x_axis) - Xyz(ref.x_axis).dot(n) * n;
  if (!(x_proj.norm() >= kNccMinAxisLength)) return nan;
  const Eigen::Vector3d x_dir = x_proj.normalized();
  const Eigen::Vector3d y_dir = n.cross(x_dir);
  const double u0 = Xyzw(ref.p[0]).dot(c.homogeneous()) / depth;
  const double v0 = Xyzw(ref.p[1]).dot(c.homogeneous()) / depth;
  const Eigen::Vector3d ju = Xyz(ref.p[0]) - u0 * Xyz(ref.p[2]);
  const Eigen::Vector3d jv = Xyz(ref.p[1]) - v0 * Xyz(ref.p[2]);
  const double x_pixels = std::hypot(ju.dot(x_dir), jv.dot(x_dir)) / depth;
  const double y_pixels = std::hypot(ju.dot(y_dir), jv.dot(y_dir)) / depth;
  const double min_pixels = kMinForeshortening * (ref.center.s[3] / depth);
  if (!(x_pixels >= min_pixels && y_pixels >= min_pixels)) return nan;
  // The window: reference pixels `step` apart around c's projection, each
  // sample where that pixel's ray meets the plane. The kernel's SAMPLE_STEP
  // is a float literal.
  const double step = static_cast<float>(sample_step);
  Eigen::Matrix3d m;
  for (int row = 0; row < 3; ++row) m.row(row) = Xyz(ref.p[row]).transpose();
  const Eigen::Matrix3d m_inv = m.inverse();
  const Eigen::Vector3d origin = Xyz(ref.center);
  const double plane = n.dot(c - origin);
  auto sample_point = [&](int r, int col, Eigen::Vector3d* x) {
    const Eigen::Vector3d ray =
        m_inv * Eigen::Vector3d(u0 + step * (col - half), v0 + step * (r - half), 1.0);
    const double lambda = plane / n.dot(ray);
    *x = origin + lambda * ray;
    return lambda > 0.0;  // the plane ahead of the reference along the ray
  };

  bool valid = true;
  double margin = std::numeric_limits<double>::infinity();
  for (int r = 0; r < patch_size && valid; ++r) {
    for (int col = 0; col < patch_size && valid; ++col) {
      Eigen::Vector3d x;
      if (!sample_point(r, col, &x)) {
        valid = false;
        break;
      }
      for (int v = 0; v < 2 && valid; ++v) {
        const NccCamera& camera = group.cameras[views[v]];
        const FloatImageView& image = group.images[views[v]];
        const double w = Xyzw(camera.p[2]).dot(x.homogeneous());
        if (!(w > 0.0)) {
          valid = false;
          break;
        }
        const double u = Xyzw(camera.p[0]).dot(x.homogeneous()) / w;
        const double y = Xyzw(camera.p[1]).dot(x.homogeneous()) / w;
        margin = std::min(margin, BorderDistance(image.layout, u, y));
        const double value = BilinearSampleUnchecked(image, u, y);
        if (std::isnan(value)) valid = false;
        (v == 0 ? a : b)[static_cast<size_t>(r) * patch_size + col] = value;
      }
    }
  }
  if (border_margin != nullptr) *border_margin = margin;
  if (!valid) return nan;

  if (sigma > 0.0) {
    // Same weights as ncc_weights: the spread of the 3 x 3 samples around
    // the centre, times sigma.
    const size_t mid = num_samples / 2;
    double centre[9];
    for (int r = -1, k = 0; r <= 1; ++r)
      for (int q = -1; q <= 1; ++q) centre[k++] = a[mid + r * patch_size + q];
    const double s = NccWeightScale(centre, 9, sigma);
    for (size_t k = 0; k < num_samples; ++k) {
      const double d = a[k] - a[mid];
      weight[k] = s > 0.0 ? std::exp(-0.5 * (d * d) / (s * s)) : 1.0;
    }
  }
  double sum_w = 0.0;
  double mean_a = 0.0;
  double mean_b = 0.0;
  for (size_t k = 0; k < num_samples; ++k) {
    sum_w += weight[k];
    mean_a += weight[k] * a[k];
    mean_b += weight[k] * b[k];
  }
  mean_a /= sum_w;
  mean_b /= sum_w;
  double saa = 0.0;
  double sbb = 0.0;
  double sab = 0.0;
  for (size_t k = 0; k < num_samples; ++k) {
    saa += weight[k] * (a[k] - mean_a) * (a[k] - mean_a);
    sbb += weight[k] * (b[k] - mean_b) * (b[k] - mean_b);
    sab += weight[k] * (a[k] - mean_a) * (b[k] - mean_b);
  }
  const double min_sum = static_cast<double>(kNccMinVariance) * sum_w;
  if (!(saa >= min_sum && sbb >= min_sum)) return nan;
  return std::clamp(sab / std::sqrt(saa * sbb), -1.0, 1.0);
}

std::vector<double> NccScoreReference(const NccGroup& group, const std::vector<NccPatch>& patches,
                                      const std::vector<NccPair>& pairs, int patch_size,
                                      std::vector<double>* border_margin, double sigma_color,
                                      double sample_step) {
  NccScorerOptions options;
  options.patch_size = patch_size;
  options.sigma_color = sigma_color;
  options.sample_step = sample_step;
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("NccScoreReference: expected " + problem);
  group.Validate();
  ValidateNccBatch(patches, pairs, static_cast<int>(group.images.size()));

  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> scores(pairs.size(), nan);
  if (border_margin != nullptr) border_margin->assign(pairs.size(), nan);
  const long n = static_cast<long>(pairs.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < n; ++i) {
    scores[i] = NccScoreReferenceUnchecked(
        group, patches[pairs[i].patch], pairs[i].view, patch_size, sigma_color,
        border_margin ? &(*border_margin)[i] : nullptr, sample_step);
  }
  return scores;
}

}  // namespace sapmvs

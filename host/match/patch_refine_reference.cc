#include "match/patch_refine_reference.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "match/ncc_score_reference.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

constexpr double kPi = 3.14159265358979323846;

double Radians(double degrees) { return degrees * kPi / 180.0; }

// The reference's patch frame and start parameters (see patch_refiner.h).
struct Frame {
  Eigen::Vector3d origin, ray, e_x, e_y, e_z;
  double t0 = 0.0;
  double footprint = 0.0;

  Eigen::Vector3d Normal(double yaw, double pitch) const {
    return std::cos(pitch) * std::sin(yaw) * e_x + std::sin(pitch) * e_y +
           std::cos(pitch) * std::cos(yaw) * e_z;
  }
};

Frame MakeFrame(const NccCamera& ref, const NccPatch& patch) {
  Frame f;
  f.origin = Xyz(ref.center);
  const Eigen::Vector3d c0 = Xyz(patch.center);
  f.t0 = (c0 - f.origin).norm();
  f.ray = (c0 - f.origin) / f.t0;
  f.e_z = -f.ray;
  const Eigen::Vector3d x_axis = Xyz(ref.x_axis);
  f.e_x = (x_axis - x_axis.dot(f.e_z) * f.e_z).normalized();
  f.e_y = f.e_z.cross(f.e_x);
  const Eigen::Vector4d p2(ref.p[2].s[0], ref.p[2].s[1], ref.p[2].s[2], ref.p[2].s[3]);
  f.footprint = p2.dot(c0.homogeneous()) / ref.center.s[3];
  return f;
}

}  // namespace

std::vector<RefinedPatchReference> PatchRefineReference(const NccGroup& group,
                                                        const std::vector<NccPatch>& patches,
                                                        const std::vector<std::vector<int>>& views,
                                                        const PatchRefinerOptions& options) {
  const std::string problem = options.Problem();
  if (!problem.empty()) throw Error("PatchRefineReference: expected " + problem);
  group.Validate();
  ValidatePatchRefineBatch(patches, views, group.cameras);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // Single-precision step values, as the kernel receives them.
  const double angle_step = static_cast<float>(Radians(options.angle_step_deg));
  const double cos_max = std::cos(static_cast<float>(Radians(options.max_angle_deg)));
  const double depth_step = static_cast<float>(options.depth_step);

  std::vector<RefinedPatchReference> results(patches.size());
  const long num_patches = static_cast<long>(patches.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (long i = 0; i < num_patches; ++i) {
    const NccPatch& patch = patches[i];
    const Frame f = MakeFrame(group.cameras[patch.reference], patch);
    const std::vector<int>& list = views[i];
    // Mean NCC at (t, yaw, pitch); NaN when invalid.
    auto evaluate = [&](const double q[3], std::vector<double>* nccs) {
      nccs->assign(list.size(), nan);
      if (!(std::cos(q[1]) * std::cos(q[2]) >= cos_max)) return nan;
      const Eigen::Vector3d n = f.Normal(q[1], q[2]);
      const NccPatch candidate = MakeNccPatch(f.origin + q[0] * f.ray, n, patch.reference);
      for (size_t k = 0; k < list.size(); ++k) {
        (*nccs)[k] = NccScoreReferenceUnchecked(group, candidate, list[k], options.patch_size,
                                                options.sigma_color, nullptr, options.sample_step);
      }
      double sum = 0.0;
      for (double s : *nccs) {
        if (std::isnan(s)) return nan;
        sum += s;
      }
      return sum / static_cast<double>(list.size());
    };
    auto improves = [](double s, double best) {
      return !std::isnan(s) && (std::isnan(best) || s > best);
    };

    const Eigen::Vector3d n0 = Xyz(patch.normal);
    double p[3] = {f.t0, std::atan2(n0.dot(f.e_x), n0.dot(f.e_z)),
                   std::asin(std::clamp(n0.dot(f.e_y), -1.0, 1.0))};
    double step[3] = {depth_step * f.footprint, angle_step, angle_step};
    RefinedPatchReference& r = results[i];
    double score = evaluate(p, &r.view_scores);
    double margin = inf;
    std::vector<double> trial;
    int halvings = 0;
    int lead = 0;
    r.evaluations = 1;
    const int directions = SearchDirections(patch);
    for (int it = 0; it < options.iterations && halvings < options.max_halvings; ++it) {
      int moved = -1;
      for (int j = 0; j < directions && moved < 0; ++j) {
        const int k = (lead + j) % directions;
        double q[3] = {p[0], p[1], p[2]};
        q[k / 2] += (k % 2 == 0) ? step[k / 2] : -step[k / 2];
        // Out-of-range angles are skipped without a score, as in the kernel.
        if (!(std::cos(q[1]) * std::cos(q[2]) >= cos_max)) continue;
        const double s = evaluate(q, &trial);
        ++r.evaluations;
        // Each comparison is a decision float32 could take the other way.
        if (!std::isnan(s) && !std::isnan(score)) margin = std::min(margin, std::abs(s - score));
        if (improves(s, score)) {
          moved = k;
          p[k / 2] = q[k / 2];
          score = s;
          r.view_scores = trial;
        }
      }
      if (moved >= 0) {
        lead = moved;
        ++r.moves;
      } else {
        for (double& s : step) s *= 0.5;
        ++halvings;
      }
    }
    r.center = f.origin + p[0] * f.ray;
    r.normal = f.Normal(p[1], p[2]);
    r.score = score;
    r.depth_offset = (p[0] - f.t0) / f.footprint;
    r.yaw = p[1];
    r.pitch = p[2];
    r.decision_margin = margin;
  }
  return results;
}

}  // namespace sapmvs
